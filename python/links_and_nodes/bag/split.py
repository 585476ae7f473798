"""`ln_bag split`: one recording into pieces BASE_0000.mcap, BASE_0001.mcap, ... by size
(a piece ends once its bytes reach SIZE) or by duration (a piece ends before the first
sample S seconds or more after the piece's first).  Samples stay in file order, so the
pieces one after the other hold exactly the input's samples; every piece repeats the
channels of the pieces before it, with the same ids.  A chunk that fits the open piece whole
(and has the output's compression) is copied as stored."""

from __future__ import annotations

import argparse
from collections.abc import Iterable

from ..mcap_format import McapError, Message, RawChunk, TopicInfo
from .copying import say
from .errors import BagError, UsageError
from .output import Output, check_output, parse_size, piece_name
from .progress import Progress
from .source import Source, first_error
from .timespec import parse_duration

HELP = "split into pieces BASE_NNNN.mcap by --size or --duration"


def add_arguments(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("--size", type=parse_size, metavar="SIZE",
                    help="bytes per piece (1GiB, 500MB, ...)")
    ap.add_argument("--duration", type=parse_duration, metavar="S",
                    help="seconds of publish time per piece")


class Pieces:
    """The open piece and the channels every new piece repeats."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.paths: list[str] = []
        self.infos: list[TopicInfo] = []
        self.ids: dict[int, int] = {}  # id of an input TopicInfo -> channel
        self.samples = 0
        self.copied_chunks = 0
        self.out = self._open()
        self.first_ns: int | None = None
        self.full = False  # the open piece reached --size: the next sample starts a new one

    def _open(self) -> Output:
        path = piece_name(self.args.output, len(self.paths))
        check_output(path, self.args.inputs, self.args.force)
        out = Output(path, self.args)
        self.paths.append(str(path))
        for info in self.infos:
            out.channel(info)
        return out

    def rotate(self) -> None:
        self.out.close()
        self.samples += self.out.samples
        self.copied_chunks += self.out.copied_chunks
        self.out = self._open()
        self.first_ns = None
        self.full = False

    def channel(self, info: TopicInfo) -> int:
        channel = self.ids.get(id(info))
        if channel is None:
            channel = self.ids[id(info)] = self.out.channel(info)
            if len(self.out.channels) > len(self.infos):
                self.infos.append(info)
        return channel


def run(args: argparse.Namespace) -> int:
    if (args.size is None) == (args.duration is None):
        raise UsageError("give one of --size and --duration")
    sources = [Source(p) for p in args.inputs]
    pieces = Pieces(args)
    progress = Progress("ln_bag split", enabled=None if not args.quiet else False)
    try:
        for src in sources:
            try:
                for block in src.reader.blocks():
                    if not isinstance(block, RawChunk):
                        _write(args, pieces, (block,))
                    elif not _copied(args, pieces, src, block):
                        _write(args, pieces, src.reader.chunk_messages(block))
                    progress.add_block(*((block.message_count, block.uncompressed_size)
                                         if isinstance(block, RawChunk) else (1, 0)))
            except McapError as exc:
                src.error = exc
                break
    finally:
        progress.done()
        pieces.out.close()
    return _finish(args, pieces, sources)


def _copied(args: argparse.Namespace, pieces: Pieces, src: Source, chunk: RawChunk) -> bool:
    """Copy `chunk` whole if it fits the open piece (or a new one); whether it was."""
    infos = src.chunk_infos(chunk)
    if infos is None or not src.ln_written:
        return False
    if pieces.full or (args.duration is not None and pieces.first_ns is not None
                       and chunk.start_ns - pieces.first_ns >= args.duration):
        pieces.rotate()
    w = pieces.out.writer
    first = chunk.start_ns if pieces.first_ns is None else pieces.first_ns
    fits = (args.size is None or w.offset + w.pending + len(chunk.head) + chunk.body_size
            <= args.size) and (args.duration is None or chunk.end_ns - first < args.duration)
    for info in infos:
        pieces.channel(info)
    if not fits or not pieces.out.can_copy(chunk, infos):
        return False
    pieces.first_ns = first
    pieces.out.copy_chunk(chunk)
    pieces.full = args.size is not None and w.offset >= args.size
    return True


def _write(args: argparse.Namespace, pieces: Pieces, messages: Iterable[Message]) -> None:
    """The per-sample path: a new piece where a sample would overfill the open one."""
    for info, seq, t, data in messages:
        if pieces.full or (args.duration is not None and pieces.first_ns is not None
                           and t - pieces.first_ns >= args.duration):
            pieces.rotate()
        if pieces.first_ns is None:
            pieces.first_ns = t
        pieces.out.write(pieces.channel(info), seq, t, data)
        w = pieces.out.writer
        pieces.full = args.size is not None and w.offset + w.pending >= args.size


def _finish(args: argparse.Namespace, pieces: Pieces, sources: list[Source]) -> int:
    total = pieces.samples + pieces.out.samples
    copied = pieces.copied_chunks + pieces.out.copied_chunks
    said = f" ({copied} chunks copied as stored)" if copied else ""
    say(args, f"{total} samples into {len(pieces.paths)} pieces{said}: "
        f"{', '.join(pieces.paths)}")
    error = first_error(sources)
    if error is not None:
        raise BagError(f"{error} (the pieces hold the samples before it)")
    return 0
