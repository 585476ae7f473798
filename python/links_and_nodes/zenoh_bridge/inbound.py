"""Inbound topics (Zenoh -> links_and_nodes): one Zenoh subscription per inbound rule, and per
topic a queue (1 sample in latest mode, the rule's buffers when queued) and a thread that
publishes here; once a topic is set up, a sample that finds its queue empty is published
directly in Zenoh's thread.

The first good sample of a topic decides its md: the name and layout hash in its attachment,
the class from the local md or, if the md is not known here, from the text the remote bridge
serves (mds.py).  A layout hash that differs from the local md, or a local topic of that name
with another layout, refuses the topic (one log line naming both hashes); the other topics go
on.  Samples without a valid attachment, or whose size is not the md's, are dropped and
counted, never published.

With the native core (native.py) the rule's subscription is the core's: it hands samples of
keys it does not know to `InRule._on_key` here.  Once a topic is set up, the topic's thread
publishes what waits in its queue and hands the topic over with `ready`, holding the queue's
lock, so a sample that meanwhile reached `offer` goes to the core after them; from then on
the core checks and publishes the topic's samples itself, in order.  While the remote bridge
offers batches (its `P/@live/batch` token; bridge.py) the core's subscription is to its batch
keys instead (`set_batch`), and the samples of a batch come here, or are handled, one by one.

While a queued topic is set up its queue (the rule's buffers) fills; a sample that finds it
full waits up to SETUP_WAIT_S for room (Zenoh holds the sender back meanwhile) before the
oldest is dropped (`superseded`), and after such a wait the next ones do not wait until there
is room again, so a slow md fetch costs the link one pause.
"""

from __future__ import annotations

import ctypes
import threading
import time
from collections import deque
from typing import Any

from .config import TopicRule
from .mds import LayoutMismatch, MdUnavailable
from .wire import (
    Attachment,
    AttachmentError,
    decode_attachment,
    matches,
    name_in,
    pattern_key,
    topic_key,
)

MD_RETRY = 2.0  # seconds before an md that could not be had is asked for again
COMPLAIN_EVERY = 5.0  # seconds between log lines about the same kind of bad sample
MAX_TOPICS = 1024  # topics one inbound rule takes; samples of further names are counted only
# Seconds a write of a queued topic waits for a subscriber here that has no free buffer
# (through a publisher with wait_for_subscribers): meanwhile the sender is held back.  Then the
# sample is written through a second publisher that does not wait (that subscriber loses its
# oldest sample, the others get it: `forced`) and the topic is congested: writes do not wait
# until one finds room again, so a subscriber that stopped reading costs one pause, not one
# per sample.  The native core does the same (ln_zenoh_core/src/inbound.rs).
HOLD_S = 0.05
SETUP_WAIT_S = 1.0  # queued: how long a sample waits for room in the topic's queue


class InTopic:
    def __init__(self, bridge: Any, name: str, rule: TopicRule, native: Any = None) -> None:
        self.bridge = bridge
        self.name = name
        self.rule = rule
        self.remote = rule.remote or ""
        self.native = native  # the rule's native.InRule, or None
        self.handed_over = False
        self._congested = False
        self._queue_stalled = False  # a sample waited SETUP_WAIT_S for room in vain
        self.stats = bridge.stats.topic(name, "in")
        self.stats.state = "waiting for a sample"
        self.queue: deque[tuple[bytes, bytes | None]] = deque(maxlen=rule.depth)
        self._cond = threading.Condition()
        self._handling = threading.Lock()  # held while a sample is handled (see offer)
        self._stop = False
        self.port: Any = None  # publishes without waiting
        self.wait_port: Any = None  # queued: publishes with wait_for_subscribers
        self.md: tuple[str, int] | None = None
        self.refused: tuple[str, int] | None = None
        self._size = 0
        self._retry_at = 0.0
        self._next_ok = 0.0
        self._interval = 1.0 / rule.rate if rule.rate else 0.0
        self._complained: dict[str, float] = {}
        self._thread = threading.Thread(target=self._run, daemon=True, name=f"in {name}")
        self._thread.start()

    def offer(self, payload: bytes, attachment: bytes | None) -> None:
        """A sample from Zenoh, called in Zenoh's thread.  Once the topic is set up and
        nothing waits in its queue it is published right here (no thread hand-over);
        otherwise it is queued for the topic's thread, which alone may block (md fetch).  Once
        the topic is handed over to the core, the core has it."""
        if self.handed_over:
            self._to_core(payload, attachment)
            return
        if self.md is not None and self._handling.acquire(blocking=False):
            try:
                with self._cond:
                    inline = not self.queue and not self.handed_over
                if inline:
                    self.stats.received += 1
                    self._handle_safely(payload, attachment)
                    if self.native is not None and self.port is not None:
                        self._hand_over()
                    return
            finally:
                self._handling.release()
        with self._cond:
            if self.rule.queued:
                self._wait_for_room()
            if not self.handed_over:
                self.stats.received += 1
                if len(self.queue) == self.queue.maxlen:
                    self.stats.superseded += 1
                self.queue.append((payload, attachment))
                self._cond.notify_all()
                return
        self._to_core(payload, attachment)

    def _wait_for_room(self) -> None:
        """Under _cond: wait (SETUP_WAIT_S at most) while the queue is full."""
        maxlen = self.queue.maxlen
        if len(self.queue) < maxlen:
            self._queue_stalled = False
            return
        if self._queue_stalled:
            return
        deadline = time.monotonic() + SETUP_WAIT_S
        while len(self.queue) == maxlen and not (self.handed_over or self._stop):
            left = deadline - time.monotonic()
            if left <= 0:
                self._queue_stalled = True
                return
            self._cond.wait(left)

    def _to_core(self, payload: bytes, attachment: bytes | None) -> None:
        if not self.native.offer(topic_key(self.remote, self.name), payload, attachment):
            self.stats.errors += 1  # cannot be: handed-over topics stay with the core

    def _hand_over(self) -> None:
        """Give the topic to the core: in Zenoh's thread right after a sample was published
        inline, or in the topic's thread after it published the queue holding its lock; so
        nothing is left here and the order is kept."""
        from .native import CoreError, Counters

        if self.handed_over or self.md is None:
            return
        counters = Counters(last_seq=self.stats.last_seq)
        try:
            self.native.ready(topic_key(self.remote, self.name), self.port, self.wait_port,
                              self.md[0], self.md[1], self.rule.rate, self._congested,
                              counters, f"topic '{self.name}' from {self.remote}")
        except CoreError as exc:
            self.native = None  # stays here, in Python
            self.bridge.say(f"topic '{self.name}': stays in Python: {exc}")
            return
        self.bridge.stats.add_native(self.name, "in", counters)
        self.handed_over = True

    def _run(self) -> None:
        while True:
            with self._cond:
                while not self.queue and not self._stop:
                    self._cond.wait()
                if self._stop:
                    return
            # Samples are handled under _handling, taken before the queue is looked at: a
            # sample handled inline by offer() never overtakes a queued one.
            with self._handling:
                with self._cond:
                    item = self.queue.popleft() if self.queue else None
                    self._cond.notify_all()  # room for a sample waiting in offer()
                if item is not None:
                    self._handle_safely(*item)
                if (self.native is not None and self.port is not None
                        and not self.handed_over):
                    with self._cond:  # offer() waits: what it has comes after the queue
                        while self.queue:
                            self._handle_safely(*self.queue.popleft())
                        self._hand_over()
                        self._cond.notify_all()

    def _handle_safely(self, payload: bytes, attachment: bytes | None) -> None:
        try:
            self._handle(payload, attachment)
        except Exception as exc:  # noqa: BLE001 - counted and said; the topic goes on
            self.stats.errors += 1
            self._complain("error", f"publishing failed: {type(exc).__name__}: {exc}")

    def _complain(self, kind: str, text: str) -> None:
        now = time.monotonic()
        if now - self._complained.get(kind, -COMPLAIN_EVERY) >= COMPLAIN_EVERY:
            self._complained[kind] = now
            self.bridge.say(f"topic '{self.name}' from {self.remote}: {text}")

    def _handle(self, payload: bytes, raw_attachment: bytes | None) -> None:
        stats = self.stats
        try:
            att = decode_attachment(raw_attachment)
        except AttachmentError as exc:
            stats.bad_attachment += 1
            self._complain("attachment", f"sample dropped: {exc} (counted as bad_attachment)")
            return
        md = (att.md_name, att.layout_hash)
        if md == self.refused:
            stats.refused += 1
            return
        if self.md is None and not self._setup(att):
            return
        if md != self.md:
            stats.refused += 1
            assert self.md is not None
            self._complain("md", f"sample of md '{att.md_name}' 0x{att.layout_hash:016x} "
                           f"dropped: this topic carries '{self.md[0]}' 0x{self.md[1]:016x}")
            return
        if len(payload) != self._size:
            stats.bad_size += 1
            self._complain("size", f"sample of {len(payload)} bytes dropped: md "
                           f"'{att.md_name}' has {self._size} (counted as bad_size)")
            return
        if stats.last_seq and att.seq > stats.last_seq + 1:
            stats.gaps += att.seq - stats.last_seq - 1
        stats.last_seq = att.seq
        if self._interval:
            now = time.monotonic()
            if now < self._next_ok:
                stats.rate_limited += 1
                return
            self._next_ok = now + self._interval
        ctypes.memmove(self._address, payload, self._size)
        self._write()
        stats.published += 1
        stats.bytes += self._size

    def _write(self) -> None:
        """Publish the sample in self.port.packet (queued: see HOLD_S)."""
        if self.wait_port is None:
            self.port.write()
            return
        from .. import LnError

        try:
            self.wait_port.write(self.port.packet, timeout=0.0 if self._congested else HOLD_S)
            self._congested = False
            return
        except LnError as exc:
            if type(exc).__name__ not in ("LnTimeoutError", "LnAgainError"):
                raise
        if not self._congested:
            self._congested = True
            self._complain("forced", f"a subscriber here took no sample for {HOLD_S} s: it "
                           "loses its oldest ones (counted as forced) until it reads again")
        self.stats.forced += 1
        self.port.write()

    def _setup(self, att: Attachment) -> bool:
        """Find the md of the topic's first good sample and publish the topic here; False if
        that cannot be done (now, or at all: refused)."""
        stats = self.stats
        if time.monotonic() < self._retry_at:
            stats.md_unavailable += 1
            return False
        try:
            cls = self.bridge.mds.resolve(att.md_name, att.layout_hash, self.remote)
        except LayoutMismatch as exc:
            return self._refuse(att, str(exc))
        except MdUnavailable as exc:
            stats.md_unavailable += 1
            self._retry_at = time.monotonic() + MD_RETRY
            stats.state = "md unavailable"
            self.bridge.say(f"topic '{self.name}' from {self.remote}: {exc}; "
                            f"asking again in {MD_RETRY:g} s")
            return False
        from .. import LnError

        self.bridge.on_inbound_published(self.name)  # never sent back out, also not meanwhile
        port = None
        try:
            port = self.bridge.client.publish(self.name, att.md_name)
            if self.rule.queued:
                self.wait_port = self.bridge.client.publish(self.name, att.md_name,
                                                            wait_for_subscribers=True)
        except LnError as exc:
            if port is not None:
                port.close()
            if type(exc).__name__ == "LnLayoutError":
                return self._refuse(att, f"the topic here has another layout than remote "
                                    f"0x{att.layout_hash:016x}: {exc}")
            stats.errors += 1
            self._retry_at = time.monotonic() + MD_RETRY
            self.bridge.say(f"topic '{self.name}': cannot publish it here: {exc}")
            return False
        self.port = port
        self._size = ctypes.sizeof(cls)
        self._address = ctypes.addressof(port.packet)
        self.md = (att.md_name, att.layout_hash)
        self.refused = None
        stats.md_name = att.md_name
        stats.state = "publishing"
        self.bridge.say(f"topic '{self.name}': publishing samples from {self.remote} here "
                        f"(md '{att.md_name}', layout 0x{att.layout_hash:016x})")
        return True

    def _refuse(self, att: Attachment, why: str) -> bool:
        self.refused = (att.md_name, att.layout_hash)
        self.stats.refused += 1
        self.stats.state = "refused: layout mismatch"
        self.bridge.say(f"error: topic '{self.name}' from {self.remote} is not published "
                        f"here: {why}")
        return False

    def close(self) -> None:
        with self._cond:
            self._stop = True
            self._cond.notify()
        self._thread.join()
        if self.handed_over and self.native is not None:
            self.native.forget(topic_key(self.remote, self.name))
        for port in (self.wait_port, self.port):
            if port is not None:
                port.close()


class InRule:
    """The Zenoh subscription of one inbound rule; creates an InTopic per topic it sees."""

    def __init__(self, bridge: Any, rule: TopicRule) -> None:
        self.bridge = bridge
        self.rule = rule
        self.remote = rule.remote or ""
        self.topics: dict[str, InTopic] = {}
        self._lock = threading.Lock()
        self._closed = False
        self.key = topic_key(self.remote, pattern_key(rule.pattern))
        self._subscriber: Any = None
        self.native: Any = None
        if bridge.core is not None:
            self.native = bridge.core.in_rule(self.key, self.remote or None, self._on_key)
            bridge.stats.stray_batches.append(self.native.bad_batches)
        else:
            self._subscriber = bridge.session.declare_subscriber(self.key, self._on_sample)

    def set_batch(self, on: bool) -> bool:
        """Take the remote bridge's batches instead of its per-topic samples (native core), or
        back; False if this rule cannot (Python path, or said why not)."""
        if self.native is None:
            return False
        from .native import CoreError

        try:
            self.native.set_batch(on)
        except CoreError as exc:
            self.bridge.say(f"topics from {self.remote}: batches not taken: {exc}")
            return False
        return True

    def _on_sample(self, sample: Any) -> None:
        attachment = sample.attachment
        self._on_key(str(sample.key_expr), sample.payload.to_bytes(),
                     attachment.to_bytes() if attachment is not None else None)

    def _on_key(self, key: str, payload: bytes, attachment: bytes | None) -> None:
        if self._closed:  # a sample Zenoh delivered while the rule closed
            return
        name = name_in(key, self.remote, "topic")
        if (name is None or not matches(name, self.rule.pattern)
                or self.bridge.config.topic_rule(name, "in") is not self.rule):
            return
        topic = self.topics.get(name)
        if topic is None:
            with self._lock:
                topic = self.topics.get(name)
                if topic is None:
                    if len(self.topics) >= MAX_TOPICS:  # a flood of keys costs no threads
                        self.bridge.stats.unknown_keys += 1
                        return
                    topic = self.topics[name] = InTopic(self.bridge, name, self.rule,
                                                        self.native)
        topic.offer(payload, attachment)

    def close(self) -> None:
        self._closed = True
        if self.native is not None:
            self.native.close()  # no sample reaches a topic or its port after this
        try:
            if self._subscriber is not None:
                self._subscriber.undeclare()
        except Exception:  # noqa: BLE001 - the session may be closed already
            pass
        with self._lock:
            topics = list(self.topics.values())
        for topic in topics:
            topic.close()
