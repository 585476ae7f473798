"""`ln_bag filter`: the samples of the selected topics (--topic, --regex, --exclude) into
one file, channels unchanged; a chunk of selected topics only is copied as stored, one of
unselected topics only passed over, one of both decoded."""

from __future__ import annotations

import argparse

from ..mcap_format import TopicInfo
from .copying import Rules, copy
from .errors import UsageError
from .selection import Selection, add_selection_args

HELP = "keep the topics named by --topic/--regex, without those of --exclude"


def add_arguments(ap: argparse.ArgumentParser) -> None:
    add_selection_args(ap)


def run(args: argparse.Namespace) -> int:
    if not (args.topic or args.regex or args.exclude):
        raise UsageError("give --topic, --regex or --exclude")
    selected = Selection(args)

    def wanted(info: TopicInfo) -> bool:
        return selected(info.topic)

    return copy(args, Rules(wanted=wanted))
