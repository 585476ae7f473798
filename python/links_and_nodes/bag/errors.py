"""The one error class of ln_bag: a refusal or failure whose text is the whole message
(the CLI prints it after `ln_bag: error:` and exits with status 1)."""

from __future__ import annotations


class BagError(Exception):
    """Why ln_bag refuses or stops; the text says it all."""


class UsageError(BagError):
    """Options that do not go together (exit status 2, like argparse's errors)."""
