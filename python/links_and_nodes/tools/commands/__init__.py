"""The manager's commands in one table (docs/manager.md, "Adding a command"): each command
is a Command with its Args and handler, registered once by the feature that answers it
(the table is the extension point features plug into, below them all); the manager's
Control.handle and describe(), the console (dispatch, help, completion), `ln_manager
COMMAND` and the scripting API's methods are derived from it.  Importing it is light (no
libln, nothing of the manager): the features' modules are imported on the first look."""

from .arguments import check_args, parse_words, to_request
from .errors import ControlError, ManagerError
from .local import Local
from .spec import SAME, Arg, ArgError, Command, Verb
from .table import command, commands, console_entry, describe, register, verb, verbs

__all__ = ["SAME", "Arg", "ArgError", "Command", "ControlError", "Local", "ManagerError",
           "Verb", "check_args", "command", "commands", "console_entry", "describe",
           "parse_words", "register", "to_request", "verb", "verbs"]
