"""Services across the bridge, with requests and responses as JSON objects of their fields
(wire.encode_fields: dynamic arrays and strings included).

Out: a local service is served as the queryable `P/service/<name>`; a worker thread calls the
service for each query (the query's attachment names the caller's md and layout hash, which
must be the local one) and replies with the response, or with an error reply carrying the
provider's text.  `P/info/service/<name>` answers its md name, layout hash and signature.

In: a remote bridge's service (seen through its liveliness token) is provided here under the
same name; each call is a Zenoh get on the remote queryable, whose error replies and silence
become error responses.
"""

from __future__ import annotations

import json
import queue
import threading
import time
from typing import Any

from .config import ServiceRule
from .mds import LayoutMismatch, MdUnavailable
from .wire import (
    AttachmentEncoder,
    AttachmentError,
    decode_attachment,
    decode_fields,
    encode_fields,
    live_key,
    service_info_key,
    service_key,
)

GROUP = "ln_zenoh"  # the service group (and thread pool) of inbound services
POOL_THREADS = 4
QUEUE_LIMIT = 64  # queries waiting per outbound service; more are answered "busy"
INFO_TIMEOUT = 5.0


class OutService:
    def __init__(self, bridge: Any, name: str, md_name: str, rule: ServiceRule) -> None:
        self.bridge = bridge
        self.name = name
        self.md_name = md_name
        self.rule = rule
        self.stats = bridge.stats.service(name, "out")
        self.stats.md_name = md_name
        self.svc = bridge.client.get_service(name, md_name)
        cls = self.svc.service_class
        self.layout_hash = cls.LAYOUT_HASH
        self.info = json.dumps({"md_name": md_name, "layout_hash": cls.LAYOUT_HASH,
                                "signature": cls.SIGNATURE}).encode()
        self._attachment = AttachmentEncoder(md_name, cls.LAYOUT_HASH)
        bridge.md_server.serve(md_name)
        self._queries: queue.Queue[Any] = queue.Queue(QUEUE_LIMIT)
        session = bridge.session
        self._closers = [
            session.declare_queryable(service_key(bridge.prefix, name), self._on_query),
            session.declare_queryable(service_info_key(bridge.prefix, name),
                                      lambda q: q.reply(q.key_expr, self.info)),
            session.liveliness().declare_token(live_key(bridge.prefix, "service", name)),
        ]
        self.stats.state = "serving"
        self._thread = threading.Thread(target=self._run, daemon=True, name=f"svc {name}")
        self._thread.start()

    def _on_query(self, query: Any) -> None:
        try:
            self._queries.put_nowait(query)
        except queue.Full:
            self.stats.errors += 1
            query.reply_err(f"service '{self.name}': {QUEUE_LIMIT} calls waiting".encode())

    def _run(self) -> None:
        while (query := self._queries.get()) is not None:
            try:
                self._call(query)
            finally:
                query.drop()

    def _call(self, query: Any) -> None:
        stats = self.stats
        try:
            raw = query.attachment
            att = decode_attachment(raw.to_bytes() if raw is not None else None)
            if (att.md_name, att.layout_hash) != (self.md_name, self.layout_hash):
                raise AttachmentError(
                    f"layout hash mismatch: the caller's md '{att.md_name}' has "
                    f"0x{att.layout_hash:016x}, the service's '{self.md_name}' "
                    f"0x{self.layout_hash:016x}")
            payload = query.payload
            fields = decode_fields(payload.to_bytes() if payload is not None else b"")
            self.svc.req = self.svc.request_class.from_dict(fields)
        except Exception as exc:  # noqa: BLE001 - AttachmentError, JSON, unknown fields
            stats.bad_requests += 1
            query.reply_err(f"service '{self.name}': bad request: {exc}".encode())
            return
        try:
            resp = self.svc.call(timeout=self.rule.timeout)
        except Exception as exc:  # noqa: BLE001 - LnServiceError (the provider's text), ...
            stats.errors += 1
            query.reply_err(str(exc).encode())
            return
        stats.calls += 1
        query.reply(query.key_expr, encode_fields(resp),
                    attachment=self._attachment.encode(0, time.time_ns()))

    def close(self) -> None:
        for thing in self._closers:
            try:
                thing.undeclare()
            except Exception:  # noqa: BLE001 - the session may be closed already
                pass
        self._queries.put(None)
        self._thread.join()
        self.svc.close()


class InService:
    """A remote bridge's service `name`, provided here."""

    def __init__(self, bridge: Any, name: str, rule: ServiceRule) -> None:
        self.bridge = bridge
        self.name = name
        self.rule = rule
        self.remote = rule.remote or ""
        self.stats = bridge.stats.service(name, "in")
        info = self._info()
        md_name, layout_hash = str(info["md_name"]), int(info["layout_hash"])
        self.stats.md_name = md_name
        try:
            bridge.mds.resolve(md_name, layout_hash, self.remote)
        except LayoutMismatch as exc:
            self.stats.state = "refused: layout mismatch"
            raise LayoutMismatch(f"service '{name}' from {self.remote} is not provided here: "
                                 f"{exc}") from None
        self._attachment = AttachmentEncoder(md_name, layout_hash)
        self.key = service_key(self.remote, name)
        bridge.use_service_pool()
        self.provider = bridge.client.get_service_provider(name, md_name, self._handle, GROUP)
        self.stats.state = "provided"

    def _info(self) -> dict[str, Any]:
        errors = []
        key = service_info_key(self.remote, self.name)
        for reply in self.bridge.session.get(key, timeout=INFO_TIMEOUT):
            if reply.ok is not None:
                return dict(json.loads(reply.ok.payload.to_bytes()))
            errors.append(reply.err.payload.to_bytes().decode(errors="replace"))
        raise MdUnavailable(f"service '{self.name}': no description from {key}: "
                            + ("; ".join(errors) or f"no answer in {INFO_TIMEOUT:g} s"))

    def _handle(self, request: Any) -> None:
        stats = self.stats
        replies = self.bridge.session.get(
            self.key, payload=encode_fields(request.req),
            attachment=self._attachment.encode(0, time.time_ns()), timeout=self.rule.timeout)
        for reply in replies:
            if reply.ok is not None:
                try:
                    request.respond(decode_fields(reply.ok.payload.to_bytes()))
                except Exception as exc:  # noqa: BLE001 - a response that does not fit
                    stats.bad_requests += 1
                    request.respond_error(f"bad response from {self.key}: {exc}")
                    return
                stats.calls += 1
                return
            stats.errors += 1
            request.respond_error(reply.err.payload.to_bytes().decode(errors="replace"))
            return
        stats.errors += 1
        request.respond_error(f"no answer from {self.key} over Zenoh within "
                              f"{self.rule.timeout:g} s")

    def close(self) -> None:
        self.provider.close()
