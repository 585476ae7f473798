"""The errors of the command table's two ends: ControlError (the manager refuses a command;
its text and LN_E* code go back in the answer) and ManagerError (what a client of the
manager raises when it refuses or cannot be reached).  Leaf module: imports nothing of
ours."""

from __future__ import annotations


class ControlError(Exception):
    """A command that cannot be carried out; the text goes back as {"error": TEXT}, with
    {"code": "ELIMIT"} etc. when an LN_E* name says more than "refused"."""

    def __init__(self, text: str, code: str = "") -> None:
        super().__init__(text)
        self.code = code


class ManagerError(Exception):
    """The manager refused a command or could not be reached; the text says why."""
