"""The loop that cut, filter and convert share: every input in turn into one output; what a
command keeps (channels, a publish-time range) and how it encodes a channel are its
arguments.  A chunk whose samples are all kept and copied unchanged goes to the output as
stored, without decompressing; one with none kept is passed over; only the others are
decoded sample by sample.  On a bad input the output is finished with the samples before
the bad record."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

from ..mcap_format import McapError, Message, RawChunk, TopicInfo
from .errors import BagError
from .output import Output, check_output
from .progress import Progress
from .source import Source, first_error
from .summary import read_layout

# a topic's add_channel keywords (None: copied unchanged) and its sample transform (None:
# the bytes unchanged)
Transform = Callable[[Any], Any]
ChannelPlan = Callable[[TopicInfo], tuple[dict[str, Any] | None, Transform | None]]
FIRST, LAST = -(1 << 63), (1 << 64) - 1
COPY, SKIP, DECODE = "copy", "skip", "decode"


def _unchanged(info: TopicInfo) -> tuple[None, None]:
    return None, None


def _every(info: TopicInfo) -> bool:
    return True


@dataclass
class Rules:
    """What a command keeps: the channels `wanted` accepts with start <= publish time <= end,
    encoded as `plan` says."""

    wanted: Callable[[TopicInfo], bool] = _every
    start: int = FIRST
    end: int = LAST
    plan: ChannelPlan = _unchanged
    # per input channel (by id of its TopicInfo): the channel, its output id (None: not
    # kept) and transform
    planned: dict[int, tuple[TopicInfo, int | None, Transform | None]] = field(
        default_factory=dict)


def say(args: argparse.Namespace, text: str) -> None:
    if not args.quiet:
        print(f"ln_bag {args.command}: {text}", file=sys.stderr, flush=True)


def total_samples(paths: list[str]) -> int | None:
    """Samples of the files by their summaries; None where one has none."""
    counts = [read_layout(p).message_count for p in paths]
    return None if any(c is None for c in counts) else sum(c for c in counts if c)


def copy(args: argparse.Namespace, rules: Rules) -> int:
    """Copy the samples of args.inputs that `rules` keep into args.output; exit status."""
    check_output(args.output, args.inputs, args.force)
    sources = [Source(p) for p in args.inputs]
    out = Output(args.output, args)
    progress = Progress(f"ln_bag {args.command}", total_samples(args.inputs),
                        enabled=None if not args.quiet else False)
    try:
        for src in sources:
            try:
                _copy_source(src, out, rules, progress)
            except McapError as exc:
                src.error = exc
                break
    finally:
        progress.done()
        out.close()
    return finish(args, out, sources)


def _copy_source(src: Source, out: Output, rules: Rules, progress: Progress) -> None:
    for block in src.reader.blocks():
        if not isinstance(block, RawChunk):
            progress.add_block(1, len(block[3]))
            _write_messages(out, rules, (block,))
            continue
        progress.add_block(block.message_count, block.uncompressed_size)
        verdict = _verdict(src, block, out, rules)
        if verdict == COPY:
            out.copy_chunk(block)
        elif verdict == DECODE:
            _write_messages(out, rules, src.reader.chunk_messages(block))


def _verdict(src: Source, chunk: RawChunk, out: Output, rules: Rules) -> str:
    """COPY `chunk` as stored, SKIP it (nothing in it is kept) or DECODE it."""
    infos = src.chunk_infos(chunk)
    if infos is None or not src.ln_written:  # times may not be publish times
        return DECODE
    if chunk.end_ns < rules.start or chunk.start_ns > rules.end:
        return SKIP
    kept = [_plan(out, rules, info)[1] is not None for info in infos]
    if not any(kept):
        return SKIP
    if not all(kept) or chunk.start_ns < rules.start or chunk.end_ns > rules.end:
        return DECODE
    if any(_plan(out, rules, info)[2] is not None for info in infos):
        return DECODE
    return COPY if out.can_copy(chunk, infos) else DECODE


def _plan(out: Output, rules: Rules, info: TopicInfo
          ) -> tuple[TopicInfo, int | None, Transform | None]:
    planned = rules.planned.get(id(info))
    if planned is None:
        channel, transform = None, None
        if rules.wanted(info):
            spec, transform = rules.plan(info)
            channel = out.channel(info, spec)
        planned = rules.planned[id(info)] = (info, channel, transform)
    return planned


def _write_messages(out: Output, rules: Rules, messages: Iterable[Message]) -> None:
    """The per-sample path: each kept message through its transform into the writer."""
    write = out.writer.write
    planned, start, end = rules.planned, rules.start, rules.end
    n = 0
    for info, seq, t_ns, data in messages:
        plan = planned.get(id(info)) or _plan(out, rules, info)
        channel = plan[1]
        if channel is None or not start <= t_ns <= end:
            continue
        transform = plan[2]
        write(channel, seq, t_ns, data if transform is None else transform(data))
        n += 1
    out.samples += n


def finish(args: argparse.Namespace, out: Output, sources: list[Source]) -> int:
    """The closing line and the exit status after `out` is closed."""
    error = first_error(sources)
    copied = f" ({out.copied_chunks} chunks copied as stored)" if out.copied_chunks else ""
    say(args, f"{out.samples} samples of {len(out.channels)} topics into {out.path}{copied}")
    if error is not None:
        raise BagError(f"{error} ({out.path} holds the samples before it)")
    return 0
