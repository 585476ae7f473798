"""Publish-time order with bounded memory: a reordering window per input (a file holds each
topic in order but the topics interleaved as the recorder read them), a k-way merge of the
inputs, and the removal of samples seen twice, by (topic, seq), within the window."""

from __future__ import annotations

import heapq
from collections import deque
from collections.abc import Iterable, Iterator

from ..mcap_format import Sample, TopicInfo

Item = tuple[TopicInfo, Sample]
WINDOW_NS = 1_000_000_000  # how far a file's samples may be out of publish-time order


def in_time_order(items: Iterable[Item], window_ns: int = WINDOW_NS) -> Iterator[Item]:
    """`items` by publish time: each is held until a sample `window_ns` later was read.
    Ties keep file order."""
    heap: list[tuple[int, int, Item]] = []
    for n, item in enumerate(items):
        t = item[1].publish_time_ns
        heapq.heappush(heap, (t, n, item))
        while heap[0][0] < t - window_ns:
            yield heapq.heappop(heap)[2]
    while heap:
        yield heapq.heappop(heap)[2]


def merged(inputs: list[Iterable[Item]], window_ns: int = WINDOW_NS) -> Iterator[Item]:
    """The samples of all inputs by publish time (ties: input order)."""
    streams = [_keyed(k, in_time_order(items, window_ns)) for k, items in enumerate(inputs)]
    for _t, _k, _n, item in heapq.merge(*streams):
        yield item


def _keyed(k: int, items: Iterable[Item]) -> Iterator[tuple[int, int, int, Item]]:
    for n, item in enumerate(items):
        yield item[1].publish_time_ns, k, n, item


def unique(items: Iterable[Item], window_ns: int = WINDOW_NS) -> Iterator[Item]:
    """`items` (in publish-time order) without a (topic, seq) seen in the last `window_ns`:
    the same sample logged by two hosts carries the same topic, seq and publish time."""
    seen: set[tuple[str, int]] = set()
    recent: deque[tuple[int, tuple[str, int]]] = deque()
    for info, s in items:
        t = s.publish_time_ns
        while recent and recent[0][0] < t - window_ns:
            seen.discard(recent.popleft()[1])
        key = (s.topic, s.seq)
        if key in seen:
            continue
        seen.add(key)
        recent.append((t, key))
        yield info, s
