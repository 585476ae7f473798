"""ln_foxglove: a links_and_nodes client that serves topics and services over the Foxglove
WebSocket protocol, for Foxglove, Lichtblick and PlotJuggler (docs/webui.md, "Foxglove and
Lichtblick").

Modules: config.py (settings, rules), schema.py (JSON Schemas from mds), front.py (the
subprotocol front: foxglove.websocket.v1 and foxglove.sdk.v1 on one port), link.py (CONTROL
commands to the manager), topics.py (a topic as a channel), services.py (a service as a
Foxglove service), bridge.py (the whole bridge) and cli.py (`ln_foxglove`).  Only topics.py,
services.py and bridge.py import `foxglove` (PyPI foxglove-sdk, an optional dependency:
`pip install foxglove-sdk`).
"""
