"""The manager's answers: turns decoded requests of one connection into registry changes
and segment operations, and those into reply messages; unlinks the socket files of
services it removes.  Knows nothing of connections or asyncio (server.py does the I/O);
keeps registry and segments consistent, also when a segment operation fails halfway."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from collections.abc import Callable
from typing import Any

from .. import _libln
from . import protocol as p
from .registry import Client, Port, PortKind, PortRequest, Registry, RequestError, Topic
from .runtime import remove_service_socket
from .segments import Segments
from .services import Service, ServiceOffer, Services

log = logging.getLogger("ln_manager")

_CODES = {cls.name: code for code, cls in _libln.ERRORS_BY_CODE.items()}
_MAX_PID = (1 << 31) - 1  # pids travel as i32 into the reader slots


def error_code(name: str) -> int:
    """The LN_E* number of a table name ("ELIMIT" -> -11)."""
    return _CODES[name]


def _transport_note(flags: int) -> str:
    """For the port log line: the transport a subscriber asked for, if any."""
    if flags & p.SUBSCRIBE_TCP:
        return ", transport tcp"
    if flags & p.SUBSCRIBE_UDP:
        return ", transport udp"
    return ""


def _service_entry(service: Service) -> p.ServiceEntry:
    o = service.offer
    return p.ServiceEntry(o.name, o.md_name, o.layout_hash, service.provider.name, o.group,
                          o.host_id, o.unix_path, o.tcp_host, o.tcp_port, service.calls,
                          service.errors)


@dataclass(eq=False)
class Session:
    """One connection: its peer address and, after HELLO, its client."""

    address: str
    client: Client | None = None

    @property
    def label(self) -> str:
        """How logs name the connection: `client NAME (ADDR)`."""
        name = self.client.name if self.client else "?"
        return f"client {name} ({self.address})"


class HandshakeRefused(Exception):
    """HELLO was answered with ERROR; the connection must be closed after sending it."""

    def __init__(self, reply: p.Error) -> None:
        super().__init__(reply.text)
        self.reply = reply


class Core:
    def __init__(self, instance: str, registry: Registry, segments: Segments,
                 services: Services | None = None) -> None:
        self.instance = instance
        self.registry = registry
        self.segments = segments
        self.service_registry = services if services is not None else Services()
        # Called after every change of clients, ports or services (the scheduler's readiness
        # and watchdog checks wait on them instead of polling).
        self.listeners: list[Callable[[], None]] = []

    def _changed(self) -> None:
        for listener in list(self.listeners):
            listener()

    def topic_publishers(self, name: str) -> int:
        """Publishers of topic `name` now (0 if there is no such topic)."""
        topic = self.registry.topics.get(name)
        return topic.publishers if topic is not None else 0

    def topic_published(self, name: str) -> int:
        """Samples topic `name` has had (0 if there is no such topic)."""
        topic = self.registry.topics.get(name)
        return self.segments.published(topic.id) if topic is not None else 0

    def service_provided(self, name: str) -> bool:
        return name in self.service_registry.by_name

    # ---- handshake ----------------------------------------------------------------------
    def check_version(self, version: int) -> None:
        if version != p.VERSION:
            raise HandshakeRefused(p.Error(0, error_code("EVERSION"),
                                           f"client speaks protocol {version}, manager "
                                           f"speaks {p.VERSION}"))

    def hello(self, session: Session, hello: p.Hello) -> p.Welcome:
        """Register the client of a HELLO whose version was checked; HandshakeRefused if
        its name or pid is unusable."""
        self.check_version(hello.version)
        try:
            if hello.pid > _MAX_PID:
                raise RequestError("EINVAL", f"pid {hello.pid} out of range")
            client = self.registry.add_client(hello.client_name, hello.pid, session.address,
                                              hello.libln_version, hello.host_id)
        except RequestError as exc:
            raise HandshakeRefused(p.Error(0, error_code(exc.code), exc.text)) from None
        session.client = client
        return p.Welcome(p.VERSION, client.id, client.name, self.instance)

    # ---- requests -----------------------------------------------------------------------
    def request(self, session: Session, msg: p.Message) -> p.Message:
        """The reply to one request of a registered client; refusals become ERROR."""
        try:
            return self._request(session, msg)
        finally:
            self._changed()

    def _request(self, session: Session, msg: p.Message) -> p.Message:
        assert session.client is not None
        request_id = msg.request_id  # type: ignore[attr-defined]
        try:
            if isinstance(msg, p.Publish | p.Subscribe):
                return self._open_port(session, msg)
            if isinstance(msg, p.ClosePort):
                port = self.registry.find_port(session.client, msg.port_id)
                log.info("%s: closing port %d of topic %r", session.label, msg.port_id,
                         port.topic.name)
                self._close_port(port)
                return p.Ok(request_id)
            if isinstance(msg, p.TopicInfo):
                topic = self.registry.topic(msg.topic)
                return p.TopicInfoOk(request_id, topic.md_name, topic.layout_hash,
                                     topic.message_size, topic.publishers, topic.subscribers)
            if isinstance(msg, p.RegisterService | p.UnregisterService | p.FindService
                          | p.ServiceCalled):
                return self._service_request(session, msg)
            if isinstance(msg, p.ListServices):
                return p.service_list(request_id, map(_service_entry,
                                                      self.service_registry.sorted()))
        except RequestError as exc:
            # an unknown topic or service asked for is an answer, not an event worth a line
            level = (logging.DEBUG if isinstance(msg, p.TopicInfo | p.FindService)
                     and exc.code == "ENOTFOUND" else logging.INFO)
            log.log(level, "%s: %s refused: %s: %s", session.label, msg.TYPE.name, exc.code,
                    exc.text)
            return p.Error(request_id, error_code(exc.code), exc.text)
        raise AssertionError(f"not a request: {msg.TYPE.name}")

    def disconnect(self, session: Session) -> int:
        """Release everything the session's client held; how many ports."""
        client = session.client
        if client is None:
            return 0
        gone = self.service_registry.remove_client(client)
        for service in gone:
            log.info("service %r of %s removed: its client disconnected (%d calls, %d "
                     "errors)", service.name, session.label, service.calls, service.errors)
        self._remove_sockets(gone)
        ports = list(client.ports.values())
        for port in ports:
            self._close_port(port)
        self.registry.remove_client(client)
        self._changed()
        return len(ports)

    def shutdown(self) -> int:
        """Release every client and unlink every segment; how many segments."""
        for client in list(self.registry.clients.values()):
            self.disconnect(Session(client.address, client))
        return self.segments.remove_all()

    def services(self) -> list[dict[str, Any]]:
        """Every registered service as plain data (docs/manager.md, "Services"), by name."""
        return self.service_registry.listing()

    # ---- services -----------------------------------------------------------------------
    def _service_request(self, session: Session,
                         msg: p.RegisterService | p.UnregisterService | p.FindService
                         | p.ServiceCalled) -> p.Message:
        client = session.client
        assert client is not None
        services = self.service_registry
        if isinstance(msg, p.RegisterService):
            offer = ServiceOffer(msg.name, msg.md_name, msg.layout_hash, msg.signature,
                                 msg.group, msg.host_id, msg.unix_path, msg.tcp_host,
                                 msg.tcp_port)
            _, old = services.register(client, offer)
            where = ", ".join(([f"unix {offer.unix_path}"] if offer.unix_path else [])
                              + ([f"tcp {offer.tcp_host}:{offer.tcp_port}"]
                                 if offer.tcp_port else []))
            log.info("%s: service %r %s: md %r (hash 0x%016x), signature %r, group %r, "
                     "host %r, %s", session.label, offer.name,
                     "re-registered" if old else "registered", offer.md_name,
                     offer.layout_hash, offer.signature, offer.group, offer.host_id, where)
            return p.Ok(msg.request_id)
        if isinstance(msg, p.UnregisterService):
            service = services.unregister(client, msg.name)
            log.info("%s: service %r unregistered (%d calls, %d errors)", session.label,
                     service.name, service.calls, service.errors)
            self._remove_sockets([service])
            return p.Ok(msg.request_id)
        if isinstance(msg, p.FindService):
            service = services.find(msg.name, msg.md_name, msg.layout_hash)
            o = service.offer
            return p.ServiceInfo(msg.request_id, service.provider.name, o.host_id,
                                 o.unix_path, o.tcp_host, o.tcp_port, o.signature)
        service = services.called(client, msg.name, msg.calls, msg.errors)
        log.debug("%s: service %r: %d calls, %d errors", session.label, service.name,
                  service.calls, service.errors)
        return p.Ok(msg.request_id)

    def _remove_sockets(self, gone: list[Service]) -> None:
        """Unlink the unix sockets of removed services that no remaining service offers
        (runtime.remove_service_socket decides which files may go)."""
        for path in sorted({s.offer.unix_path for s in gone if s.offer.unix_path}):
            if self.service_registry.unix_path_in_use(path):
                log.debug("left service socket %s: another service still offers it", path)
                continue
            reason = remove_service_socket(path)
            if reason is None:
                log.info("removed service socket %s", path)
            else:
                log.debug("left service socket %s: %s", path, reason)

    # ---- ports --------------------------------------------------------------------------
    def _open_port(self, session: Session, msg: p.Publish | p.Subscribe) -> p.PortOk:
        assert session.client is not None
        kind = PortKind.PUBLISHER if isinstance(msg, p.Publish) else PortKind.SUBSCRIBER
        request = PortRequest(kind, msg.topic, msg.md_name, msg.layout_hash, msg.message_size,
                              msg.buffers, msg.flags)
        plan = self.registry.plan_port(session.client, request)
        topic = plan.topic
        if topic is None:
            segment = self.segments.create(plan.topic_id, request.topic, request.md_name,
                                           request.layout_hash, request.message_size,
                                           plan.slots)
            topic = self.registry.add_topic(plan)
            log.info("topic %r created by %s: md %r (hash 0x%016x, %d bytes), %d slots in %s",
                     topic.name, session.label, topic.md_name, topic.layout_hash,
                     topic.message_size, topic.slots, segment)
        elif plan.grow_to is not None:
            segment = self.segments.grow(topic.id, topic.md_name, topic.layout_hash,
                                         topic.message_size, plan.grow_to)
            log.info("topic %r grown from %d to %d slots for %s: now %s", topic.name,
                     topic.slots, plan.grow_to, session.label, segment)
            self.registry.grow_topic(topic, plan.grow_to)
        try:
            if plan.reader_index is not None:
                self.segments.reserve_reader(topic.id, plan.reader_index, session.client.pid,
                                             request.buffers)
        except RequestError:
            self._drop_if_unused(topic)
            raise
        port = self.registry.add_port(plan, topic)
        try:
            self.segments.set_counts(topic.id, topic.publishers, topic.subscribers)
        except RequestError:
            self._close_port(port)
            raise
        segment = self.segments.current(topic.id)
        log.info("%s: %s %r -> port %d, %s%s%s", session.label, kind.value, topic.name, port.id,
                 segment, "" if port.reader_index is None else f" reader {port.reader_index}",
                 _transport_note(port.flags))
        reader = p.NO_READER if port.reader_index is None else port.reader_index
        return p.PortOk(msg.request_id, port.id, segment, reader)

    def _close_port(self, port: Port) -> None:
        topic = port.topic
        if port.reader_index is not None:
            self.segments.release_reader(topic.id, port.reader_index)
        if self.registry.remove_port(port):
            self._remove_segments(topic.id, topic.name)
            return
        try:
            self.segments.set_counts(topic.id, topic.publishers, topic.subscribers)
        except RequestError as exc:
            log.warning("%s", exc.text)

    def _drop_if_unused(self, topic: Topic) -> None:
        if self.registry.drop_topic_if_unused(topic):
            self._remove_segments(topic.id, topic.name)

    def _remove_segments(self, topic_id: int, name: str) -> None:
        removed = self.segments.remove(topic_id)
        log.info("topic %r has no ports left: removed %s", name, ", ".join(removed))
