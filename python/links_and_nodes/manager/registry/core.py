"""The manager's answers: turns decoded requests of one connection into registry changes
and ring operations, and those into reply messages; unlinks the socket files of services
it removes.  Knows nothing of connections (server.py does the I/O); keeps registry and
rings consistent, also when a ring operation fails halfway.  Rings live on the host of the
port that needs them: the manager's own host through libln (LocalRings), other hosts
through their ln_daemon (network.py); requests are handled one at a time, since a remote
ring operation awaits its daemon."""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from ... import _libln
from ...tools import protocol as p
from .access import Access
from .logs import LogBatchError, LogStore
from .model import Client, Port, PortKind, PortPlan, PortRequest, Registry, RequestError, Topic
from .rings import LocalRings, Rings
from .runtime import purge_service_sockets, remove_service_socket
from .segments import AdoptedRing, Segments
from .service_security import ServiceSecurity
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
    # How the client was admitted (admission.py), for the log: "user 1000 (ada)", "key" ...
    admitted: str = ""
    # Derived by admission by key (docs/security.md); None after admission by credentials.
    session_key: bytes | None = None

    @property
    def label(self) -> str:
        """How logs name the connection: `client NAME (ADDR)`."""
        name = self.client.name if self.client else "?"
        return f"client {name} ({self.address})"


class HostRings(Protocol):
    """Which host's rings a client's ports use (network.Network implements it)."""

    def rings_for(self, client: Client) -> Rings:
        """The rings of the client's host; RequestError if that host cannot have any."""
        ...

    def all_rings(self) -> list[Rings]:
        """The rings of every host (the local one included)."""
        ...

    def host_label(self, client: Client) -> str: ...

    def service_host(self, caller: Client, provider: Client, tcp_host: str) -> str:
        """The provider's TCP address as the caller reaches it: a loopback address (the
        provider talks to the manager over loopback) becomes its host's network address."""
        ...

    async def identify(self, client: Client) -> None:
        """Wait (boundedly) until the client's host is known, e.g. while the daemon that
        started it has not told its host id yet."""
        ...


class HandshakeRefused(Exception):
    """HELLO was answered with ERROR; the connection must be closed after sending it."""

    def __init__(self, reply: p.Error) -> None:
        super().__init__(reply.text)
        self.reply = reply


class Core:
    def __init__(self, instance: str, registry: Registry, segments: Segments,
                 services: Services | None = None,
                 hosts: Callable[[Core], HostRings] | None = None,
                 logs: LogStore | None = None,
                 service_security: ServiceSecurity | None = None) -> None:
        """`hosts` builds the view of the other hosts (network.Network) for a manager that
        has some, given this core (their rings and the local ones are kept consistent
        under the core's lock); None: every client is on the manager's own host."""
        self.instance = instance
        self.registry = registry
        self.segments = segments
        self.local = LocalRings(segments)
        self._lock = asyncio.Lock()
        # Called after every change of clients, ports or services (the scheduler's readiness
        # and watchdog checks wait on them instead of polling).
        self.listeners: list[Callable[[], None]] = []
        self.hosts: HostRings | None = hosts(self) if hosts is not None else None
        self.service_registry = services if services is not None else Services()
        # Provider sockets found at start-up, kept for their providers until the adoption
        # window closes (end_adoption).
        self._held_sockets: tuple[Path, list[str]] | None = None
        # The log lines of every client (LOG) and of process output (registry/logs.py).
        self.logs = logs if logs is not None else LogStore()
        # The `access` rules of the configuration (access.py); none: everything allowed.
        self.access = Access()
        # The key and level of service calls between hosts (SERVICE_KEY).
        self.service_security = service_security or ServiceSecurity()

    def _changed(self) -> None:
        for listener in list(self.listeners):
            listener()

    def topic_publishers(self, name: str) -> int:
        """Publishers of topic `name` now (0 if there is no such topic)."""
        topic = self.registry.topics.get(name)
        return topic.publishers if topic is not None else 0

    async def topic_published(self, name: str) -> int:
        """Samples topic `name` has had (0 if there is no such topic): the newest sequence
        number of the ring on its publishers' host, read now (the watchdog measures rates
        with it).  Another host's is asked of its daemon."""
        topic = self.registry.topics.get(name)
        if topic is None:
            return 0
        published = getattr(self.hosts, "published", None)
        if published is not None:
            counted = await published(topic)
            if counted is not None:  # counted on another host
                return int(counted)
        if self.segments.has(topic.id):
            return self.segments.published(topic.id)
        return 0

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
    async def request(self, session: Session, msg: p.Message) -> p.Message:
        """The reply to one request of a registered client; refusals become ERROR."""
        try:
            if self.hosts is not None and session.client is not None \
                    and isinstance(msg, p.Publish | p.Subscribe | p.ReclaimPort):
                await self.hosts.identify(session.client)  # not under the lock: it waits
            async with self._lock:
                return await self._request(session, msg)
        finally:
            self._changed()

    async def _request(self, session: Session, msg: p.Message) -> p.Message:
        assert session.client is not None
        request_id = msg.request_id  # type: ignore[attr-defined]
        try:
            self.access.check(session.client.name, msg)
            if isinstance(msg, p.Publish | p.Subscribe):
                return await self._open_port(session, msg)
            if isinstance(msg, p.ReclaimPort):
                return await self._reclaim_port(session, msg)
            if isinstance(msg, p.ClosePort):
                port = self.registry.find_port(session.client, msg.port_id)
                log.info("%s: closing port %d of topic %r", session.label, msg.port_id,
                         port.topic.name)
                await self._close_port(port)
                return p.Ok(request_id)
            if isinstance(msg, p.TopicInfo):
                topic = self.registry.topic(msg.topic)
                return p.TopicInfoOk(request_id, topic.md_name, topic.layout_hash,
                                     topic.message_size, topic.publishers, topic.subscribers)
            if isinstance(msg, p.RegisterService | p.UnregisterService | p.FindService
                          | p.ServiceCalled):
                return self._service_request(session, msg)
            if isinstance(msg, p.ServiceKey):
                return self.service_security.info(request_id,
                                                  getattr(session, "session_key", None))
            if isinstance(msg, p.ListServices):
                return p.service_list(request_id, map(_service_entry,
                                                      self.service_registry.sorted()))
        except RequestError as exc:
            # an unknown topic or service asked for is an answer, not an event worth a line
            level = (logging.DEBUG if isinstance(msg, p.TopicInfo | p.FindService)
                     and exc.code == "ENOTFOUND" else
                     logging.WARNING if isinstance(msg, p.ReclaimPort) or exc.code == "EPERM"
                     else logging.INFO)
            log.log(level, "%s: %s refused: %s: %s", session.label, msg.TYPE.name, exc.code,
                    exc.text)
            return p.Error(request_id, error_code(exc.code), exc.text)
        raise AssertionError(f"not a request: {msg.TYPE.name}")

    def log_batch(self, session: Session, msg: p.Log) -> p.Message:
        """A client's LOG batch into the log store: OK, or ERROR (EINVAL) for entries that
        do not follow the format (none of them is kept).  Not under the core's lock: it
        touches nothing else."""
        client = session.client
        assert client is not None
        try:
            self.logs.add_batch(client.name, self.client_host(client), client.pid,
                                msg.dropped, msg.count, msg.entries)
        except LogBatchError as exc:
            log.info("%s: LOG refused: %s", session.label, exc)
            return p.Error(msg.request_id, error_code("EINVAL"), f"LOG: {exc}")
        return p.Ok(msg.request_id)

    def client_host(self, client: Client) -> str:
        """The host a client runs on, as the configuration names it where the manager
        knows its hosts, else the host name of its host id."""
        if self.hosts is not None:
            return self.hosts.host_label(client)
        return client.host_id.split("/", 1)[0] or client.address.rsplit(":", 1)[0]

    # ---- adoption after a restart --------------------------------------------------------
    def adopt(self, rings: list[AdoptedRing], socket_dir: Path | None,
              sockets: list[str]) -> None:
        """Before clients come: register the topics of rings a killed predecessor left (the
        segments module adopted them) and keep the provider sockets it found in socket_dir,
        until end_adoption."""
        for ring in rings:
            try:
                self.registry.adopt_topic(ring.topic_id, ring.topic, ring.md_name,
                                          ring.layout_hash, ring.message_size, ring.slots,
                                          set(ring.readers))
            except RequestError as exc:  # segments.adopt() checked it; never a crash here
                names = self.segments.remove(ring.topic_id)
                log.warning("removed %s instead of adopting it: %s", ", ".join(names),
                            exc.text)
                continue
            log.info("adopted topic %r: md %r (hash 0x%016x, %d bytes), %d slots, sample %d, "
                     "%d reader slot%s held, in %s", ring.topic, ring.md_name,
                     ring.layout_hash, ring.message_size, ring.slots, ring.write_seq,
                     len(ring.readers), "" if len(ring.readers) == 1 else "s",
                     ", ".join(ring.names))
        if socket_dir is not None:
            self._held_sockets = (socket_dir, sockets)

    async def end_adoption(self) -> None:
        """The adoption window is over: free the reader slots of subscribers that did not
        come back, remove the adopted topics nobody took and the provider sockets nobody
        registered again."""
        async with self._lock:
            for topic in [t for t in self.registry.topics.values() if t.held]:
                unclaimed = self.registry.release_hold(topic)
                for index in unclaimed:
                    await self.local.release_reader(topic.id, index)
                if self.registry.drop_topic_if_unused(topic):
                    names = await self.local.remove(topic.id)
                    log.info("adopted topic %r was not taken back: removed %s", topic.name,
                             ", ".join(names))
                    continue
                if unclaimed:
                    log.info("topic %r: released reader slot%s %s of subscribers that did not "
                             "come back", topic.name, "" if len(unclaimed) == 1 else "s",
                             ", ".join(map(str, unclaimed)))
                try:
                    await self._set_counts(topic)
                except RequestError as exc:
                    log.warning("%s", exc.text)
            held, self._held_sockets = self._held_sockets, None
            if held is not None:
                directory, names = held
                in_use = {Path(s.offer.unix_path).name for s in self.service_registry.sorted()
                          if s.offer.unix_path
                          and Path(s.offer.unix_path).parent == directory}
                removed = purge_service_sockets(directory, [n for n in names
                                                            if n not in in_use])
                if removed:
                    log.info("removed %d service socket%s nobody registered again: %s",
                             len(removed), "" if len(removed) == 1 else "s",
                             ", ".join(removed))
        self._changed()

    @property
    def adopting(self) -> bool:
        return any(t.held for t in self.registry.topics.values()) \
            or self._held_sockets is not None

    async def disconnect(self, session: Session) -> int:
        """Release everything the session's client held; how many ports."""
        client = session.client
        if client is None:
            return 0
        async with self._lock:
            return await self._disconnect(session, client)

    async def _disconnect(self, session: Session, client: Client) -> int:
        gone = self.service_registry.remove_client(client)
        for service in gone:
            log.info("service %r of %s removed: its client disconnected (%d calls, %d "
                     "errors)", service.name, session.label, service.calls, service.errors)
        self._remove_sockets(gone)
        ports = list(client.ports.values())
        for port in ports:
            await self._close_port(port)
        self.registry.remove_client(client)
        self._changed()
        return len(ports)

    async def shutdown(self) -> int:
        """Release every client and unlink every segment; how many segments."""
        for client in list(self.registry.clients.values()):
            await self.disconnect(Session(client.address, client))
        held, self._held_sockets = self._held_sockets, None
        if held is not None:  # nobody registers them any more
            purge_service_sockets(*held)
        removed = 0
        for rings in self._every_rings():
            for topic_id in rings.topic_ids():
                removed += len(await rings.remove(topic_id))
        return removed + self.segments.remove_all()

    def transit(self) -> asyncio.Lock:
        """Held while the network changes rings outside a client's request (gateways)."""
        return self._lock

    def _every_rings(self) -> list[Rings]:
        return self.hosts.all_rings() if self.hosts is not None else [self.local]

    def _rings_for(self, client: Client) -> Rings:
        return self.hosts.rings_for(client) if self.hosts is not None else self.local

    def _topic_rings(self, topic: Topic) -> list[Rings]:
        return [r for r in self._every_rings() if r.has(topic.id)]

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
            services.found(client, msg.name)
            o = service.offer
            tcp_host = o.tcp_host
            if self.hosts is not None:
                tcp_host = self.hosts.service_host(client, service.provider, tcp_host)
            return p.ServiceInfo(msg.request_id, service.provider.name, o.host_id,
                                 o.unix_path, tcp_host, o.tcp_port, o.signature)
        service = services.called(client, msg.name, msg.calls, msg.errors)
        log.debug("%s: service %r: %d calls, %d errors", session.label, service.name,
                  service.calls, service.errors)
        return p.Ok(msg.request_id)

    def _provider_is_local(self, service: Service) -> bool:
        """Whether the service's provider runs on the manager's host: a socket path of
        another host's provider names a file there, and the same path here may be a live
        socket of a local provider (pids repeat across hosts)."""
        if self.hosts is None:
            return True
        try:
            return self.hosts.rings_for(service.provider) is self.local
        except RequestError:  # on a host this manager does not know
            return False

    def _remove_sockets(self, gone: list[Service]) -> None:
        """Unlink the unix sockets of removed services of local providers that no
        remaining service offers (runtime.remove_service_socket decides which files may
        go).  Another host's provider socket is that host's: left alone here."""
        local = set()
        for s in gone:
            if not s.offer.unix_path:
                continue
            if self._provider_is_local(s):
                local.add(s.offer.unix_path)
            else:
                log.debug("left service socket %s: its provider %s ran on another host",
                          s.offer.unix_path, s.provider.name)
        for path in sorted(local):
            if self.service_registry.unix_path_in_use(path):
                log.debug("left service socket %s: another service still offers it", path)
                continue
            reason = remove_service_socket(path)
            if reason is None:
                log.info("removed service socket %s", path)
            else:
                log.debug("left service socket %s: %s", path, reason)

    # ---- ports --------------------------------------------------------------------------
    async def _open_port(self, session: Session, msg: p.Publish | p.Subscribe) -> p.PortOk:
        client = session.client
        assert client is not None
        kind = PortKind.PUBLISHER if isinstance(msg, p.Publish) else PortKind.SUBSCRIBER
        request = PortRequest(kind, msg.topic, msg.md_name, msg.layout_hash, msg.message_size,
                              msg.buffers, msg.flags)
        plan = self.registry.plan_port(client, request)
        rings = self._rings_for(client)
        topic = plan.topic
        if topic is not None and kind is PortKind.PUBLISHER:
            self._check_publisher_host(topic, client, rings)
        if topic is None:
            segment = await rings.create(plan.topic_id, request.topic, request.md_name,
                                         request.layout_hash, request.message_size, plan.slots)
            topic = self.registry.add_topic(plan)
            log.info("topic %r created by %s: md %r (hash 0x%016x, %d bytes), %d slots in %s",
                     topic.name, session.label, topic.md_name, topic.layout_hash,
                     topic.message_size, topic.slots, segment)
        else:
            if plan.grow_to is not None:
                await self._grow(topic, plan.grow_to, session.label)
            if not rings.has(topic.id):
                segment = await rings.create(topic.id, topic.name, topic.md_name,
                                             topic.layout_hash, topic.message_size,
                                             topic.slots)
                log.info("topic %r: ring on host %r for %s: %s", topic.name, rings.host,
                         session.label, segment)
        try:
            if plan.reader_index is not None:
                await rings.reserve_reader(topic.id, plan.reader_index, client.pid,
                                           request.buffers)
        except RequestError:
            await self._drop_unused_rings(topic)
            raise
        port = await self._add_port(plan, topic)
        segment = rings.current(topic.id)
        log.info("%s: %s %r -> port %d, %s%s%s", session.label, kind.value, topic.name, port.id,
                 segment, "" if port.reader_index is None else f" reader {port.reader_index}",
                 _transport_note(port.flags))
        reader = p.NO_READER if port.reader_index is None else port.reader_index
        return p.PortOk(msg.request_id, port.id, segment, reader)

    async def _add_port(self, plan: PortPlan, topic: Topic) -> Port:
        """The planned port in the registry and the ring's counts updated; undone if the
        counts cannot be set."""
        port = self.registry.add_port(plan, topic)
        try:
            await self._set_counts(topic)
        except RequestError:
            await self._close_port(port)
            raise
        return port

    async def _reclaim_port(self, session: Session, msg: p.ReclaimPort) -> p.PortOk:
        """A reconnecting client's port on a ring it has mapped: take it back as it is."""
        client = session.client
        assert client is not None
        if msg.kind not in (p.RECLAIM_PUBLISHER, p.RECLAIM_SUBSCRIBER):
            raise RequestError("EINVAL", f"RECLAIM_PORT of kind {msg.kind}, expected "
                               f"{p.RECLAIM_PUBLISHER} or {p.RECLAIM_SUBSCRIBER}")
        kind = PortKind.PUBLISHER if msg.kind == p.RECLAIM_PUBLISHER else PortKind.SUBSCRIBER
        request = PortRequest(kind, msg.topic, msg.md_name, msg.layout_hash, msg.message_size,
                              msg.buffers, msg.flags)
        rings = self._rings_for(client)
        if rings is not self.local:
            raise RequestError("ENOTFOUND", f"topic {msg.topic!r}: only rings on the "
                               "manager's host are taken back after a restart")
        topic_id = self.segments.topic_of(msg.segment)
        if topic_id is None:
            raise RequestError("EINVAL", f"topic {msg.topic!r}: {msg.segment!r} is not a ring "
                               f"segment of instance {self.instance!r}")
        reader = None if msg.reader_index == p.NO_READER else msg.reader_index
        plan = self.registry.plan_reclaim(client, request, topic_id, reader)
        topic = plan.topic
        assert topic is not None
        if not rings.has(topic.id) or msg.segment not in self.segments.names(topic.id):
            raise RequestError("ENOTFOUND", f"topic {msg.topic!r}: segment {msg.segment!r} "
                               "is not one of its rings here")
        if plan.reader_index is not None and plan.reserve_reader:
            await rings.reserve_reader(topic.id, plan.reader_index, client.pid,
                                       request.buffers)
        port = await self._add_port(plan, topic)
        segment = rings.current(topic.id)
        log.info("%s: took back %s %r -> port %d, %s%s", session.label, kind.value,
                 topic.name, port.id, segment,
                 "" if port.reader_index is None else f" reader {port.reader_index}")
        reader_index = p.NO_READER if port.reader_index is None else port.reader_index
        return p.PortOk(msg.request_id, port.id, segment, reader_index)

    def _check_publisher_host(self, topic: Topic, client: Client, rings: Rings) -> None:
        """All publishers of a topic run on one host: the sequence numbers of its samples are
        counted in that host's ring, and every other host gets them from there."""
        for port in topic.ports.values():
            if port.kind is not PortKind.PUBLISHER:
                continue
            theirs = self._rings_for(port.client)
            if theirs is not rings:
                assert self.hosts is not None
                raise RequestError("EBUSY", f"topic {topic.name!r} already has a publisher on "
                                   f"host {self.hosts.host_label(port.client)!r} (client "
                                   f"{port.client.name!r}); the publishers of a topic must "
                                   f"run on one host, this client runs on "
                                   f"{self.hosts.host_label(client)!r}")

    async def ensure_slots(self, name: str, slots: int, label: str) -> bool:
        """Grow topic `name`'s ring to at least `slots` slots (for a reader outside the
        registry, such as a daemon's logger, that needs slack), but never past the
        per-topic ring memory limit; True if it grew.  Nothing for an unknown topic."""
        async with self._lock:
            topic = self.registry.topics.get(name)
            if topic is None or topic.slots >= slots:
                return False
            limits = self.registry.limits
            while slots > topic.slots and \
                    self.registry.ring_bytes(topic.message_size, slots) > limits.ring_memory:
                slots -= 1
            if slots <= topic.slots:
                return False
            try:
                await self._grow(topic, slots, label)
            except RequestError as exc:
                log.warning("topic %r: cannot grow its ring for %s: %s", name, label, exc.text)
                return False
        self._changed()
        return True

    async def _grow(self, topic: Topic, slots: int, label: str) -> None:
        """Replace the topic's ring by a deeper generation on every host that has one."""
        for rings in self._topic_rings(topic):
            segment = await rings.grow(topic.id, topic.md_name, topic.layout_hash,
                                       topic.message_size, slots)
            log.info("topic %r grown from %d to %d slots for %s: now %s%s", topic.name,
                     topic.slots, slots, label, segment,
                     f" on host {rings.host!r}" if rings.host else "")
        self.registry.grow_topic(topic, slots)

    async def _set_counts(self, topic: Topic) -> None:
        for rings in self._topic_rings(topic):
            await rings.set_counts(topic.id, topic.publishers, topic.subscribers)

    async def _close_port(self, port: Port) -> None:
        topic = port.topic
        if port.reader_index is not None:
            rings = self._rings_for_quietly(port.client)
            if rings is not None and rings.has(topic.id):
                await rings.release_reader(topic.id, port.reader_index)
        if self.registry.remove_port(port):
            await self._remove_rings(topic)
            return
        await self._drop_unused_rings(topic)
        try:
            await self._set_counts(topic)
        except RequestError as exc:
            log.warning("%s", exc.text)

    def _rings_for_quietly(self, client: Client) -> Rings | None:
        try:
            return self._rings_for(client)
        except RequestError:
            return None

    async def _drop_unused_rings(self, topic: Topic) -> None:
        """Remove the topic if it has no ports, else the rings of hosts without its ports
        (the network decides about rings that only pass samples on: it adds them back)."""
        if self.registry.drop_topic_if_unused(topic):
            await self._remove_rings(topic)
            return
        if topic.held:  # adopted: its ring waits for the ports that come back
            return
        used = {id(self._rings_for_quietly(port.client)) for port in topic.ports.values()}
        for rings in self._topic_rings(topic):
            if id(rings) not in used and not self._needed_elsewhere(topic, rings):
                names = await rings.remove(topic.id)
                log.info("topic %r has no ports on host %r left: removed %s", topic.name,
                         rings.host, ", ".join(names))

    def _needed_elsewhere(self, topic: Topic, rings: Rings) -> bool:
        needs = getattr(self.hosts, "transit_needed", None)
        return bool(needs and needs(topic, rings))

    async def _remove_rings(self, topic: Topic) -> None:
        removed: list[str] = []
        for rings in self._topic_rings(topic):
            removed += await rings.remove(topic.id)
        log.info("topic %r has no ports left: removed %s", topic.name, ", ".join(removed))
