"""The manager's commands in one table (docs/manager.md, "Adding a command"): each command
is a Command with its Args and handler, registered once; Control.handle and describe(), the
console (dispatch, help, completion), `ln_manager COMMAND` and the scripting API's methods
are derived from it."""

from . import phrases
from .check import check_args, parse_words, to_request
from .spec import SAME, Arg, ArgError, Command, Verb
from .table import command, commands, console_entry, describe, register, verbs

__all__ = ["SAME", "Arg", "ArgError", "Command", "Verb", "check_args", "command", "commands",
           "console_entry", "describe", "parse_words", "phrases", "register", "to_request", "verbs"]
