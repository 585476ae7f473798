"""One links_and_nodes service as a Foxglove service: requests and responses as JSON objects
of the md's fields (dynamic arrays and strings included), with a JSON Schema of each.

The sdk runs each call's handler in a thread of its own; the handler calls the service as
`ln_manager service call` does (introspect_commands.service_call_values: the request checked
against the md, the response with float32 values as they are) and answers with the response,
or fails with the reason (a bad request, the provider's error text, a timeout), which the
client gets as a serviceCallFailure.
"""

from __future__ import annotations

import json
from typing import Any

from ln_generate import MessageDef

from ..md_json import SCHEMA_ENCODING, encode, root_schema
from ..tools.introspection.commands import CommandError, Context, service_call_values
from ..zenoh_bridge.config import ServiceRule
from ..zenoh_bridge.wire import decode_fields


class ServiceCallFailed(Exception):
    """Why a call failed; the sdk sends "ServiceCallFailed: TEXT" to the client."""


def service_schema(md: MessageDef) -> Any:
    import foxglove

    def part(section: str) -> Any:
        schema = root_schema(md.sections[section], md.doc, topic=False,
                             required=section != "request")
        return foxglove.MessageSchema(encoding="json", schema=foxglove.Schema(
            name=f"{md.name}.{section}", encoding=SCHEMA_ENCODING,
            data=json.dumps(schema).encode()))

    return foxglove.ServiceSchema(md.name, request=part("request"), response=part("response"))


class BridgedService:
    """`info` is the manager's service_info answer, `md` its checked md."""

    def __init__(self, bridge: Any, info: dict[str, Any], md: MessageDef, rule: ServiceRule
                 ) -> None:
        import foxglove

        self.bridge = bridge
        self.name = str(info["name"])
        self.md_name = md.name
        self.layout_hash = md.layout_hash
        self.rule = rule
        self.calls = 0
        self.failures = 0
        self.service = foxglove.Service(self.name, schema=service_schema(md),
                                        handler=self._handle)

    def _handle(self, request: Any) -> bytes:
        bridge = self.bridge
        try:
            if request.encoding != "json":
                raise CommandError(f"request encoding {request.encoding!r}: only json is "
                                   "supported")
            try:
                values = decode_fields(bytes(request.payload))
            except (ValueError, UnicodeDecodeError) as exc:
                raise CommandError(f"bad request: {exc}") from None
            ctx = Context(bridge.link.control, bridge.address, bridge.say,
                          client_prefix=bridge.config.name)
            response = service_call_values(ctx, self.name, values, self.rule.timeout)
        except CommandError as exc:
            self.failures += 1
            bridge.say(f"service '{self.name}': call from Foxglove client {request.client_id} "
                       f"failed: {exc}", verbose=True)
            raise ServiceCallFailed(str(exc)) from None
        self.calls += 1
        return encode(response)
