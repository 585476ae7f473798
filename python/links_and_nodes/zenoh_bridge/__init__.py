"""ln_zenoh: a links_and_nodes client that bridges topics and services to Zenoh (docs/zenoh.md).

Modules: config.py (rules, the config file, the command line's topic specs), wire.py (key
expressions, the attachment, the JSON form of service fields), ros2.py (the optional
rmw_zenoh-like mapping), mds.py (md texts served and fetched), stats.py (counters),
session.py (opening the Zenoh session), outbound.py / inbound.py (topics each way),
services.py (services each way), bridge.py (the whole bridge) and cli.py (`ln_zenoh`).  Only
session.py and the modules that use a session import `zenoh` (PyPI eclipse-zenoh, an
optional dependency: `pip install eclipse-zenoh`).
"""
