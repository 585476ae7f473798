"""links_and_nodes: Python bindings of libln, the links_and_nodes client library.

    import links_and_nodes as ln
    clnt = ln.client("planner")
    pub = clnt.publish("robot.state", "robot/joint_state")
    svc = clnt.get_service("robot.set_gains", "robot/set_gains")

Importing the package loads neither libln nor numpy: generated message modules work
without libln.
The library is loaded (and its version checked) the first time something that needs it
is used: `ln.client`, `ln.service_provider` (or another class of the client API), or one
of the exception classes generated from libln's error table (``ln.LnTimeoutError`` is
the class for ``LN_ETIMEOUT``: "Ln" + table name without its leading E, capitalised,
+ "Error"; all derive from ``ln.LnError``).
"""

from typing import Any

from .errors import LibraryNotFoundError, LnError

__version__ = "0.1.0"

__all__ = ["EventResult", "LibraryNotFoundError", "LnError", "__version__",
           "add_message_definition_dir", "client", "event", "event_handler", "message_class", "provided_service", "publisher", "service",
           "service_provider", "service_request", "subscriber"]

_CLIENT_NAMES = ("client", "publisher", "subscriber")
_MD_NAMES = ("add_message_definition_dir", "message_class")
_SERVICE_NAMES = ("provided_service", "service", "service_provider", "service_request")
_EVENT_NAMES = ("EventResult", "event", "event_handler")
_PARAMETER_NAMES = ("parameter", "parameter_block")
__all__ += ["parameter", "parameter_block"]
_PULL_NAMES = ("PullSample", "pull_subscribe")
__all__ += list(_PULL_NAMES)
_WAITSET_NAMES = ("Attachment", "FdEvents", "WaitEvent", "WaitKind", "WaitSet")
__all__ += list(_WAITSET_NAMES)
__all__ += ["LogHandler"]


def __getattr__(name: str) -> Any:
    # Names that need libln are resolved on first use, which is what loads it; the message
    # types (and numpy with them) too, so the manager, which needs neither, starts faster.
    if name in _MD_NAMES:
        from . import md_loader

        return getattr(md_loader, name)
    if name in _CLIENT_NAMES:
        from . import _client as _client_module

        return getattr(_client_module, name)
    if name in _SERVICE_NAMES:
        from . import _services

        return getattr(_services, name)
    if name in _EVENT_NAMES:
        from . import _events

        return getattr(_events, name)
    if name in _PULL_NAMES:
        from . import pull

        return getattr(pull, name)
    if name in _PARAMETER_NAMES:
        from . import _parameters

        return getattr(_parameters, name)
    if name in _WAITSET_NAMES:
        from . import _waitset

        return getattr(_waitset, name)
    if name == "LogHandler":
        from . import _log_handler

        return _log_handler.LogHandler
    if name.startswith("Ln") and name.endswith("Error"):
        from . import _libln

        if name in _libln.ERROR_CLASSES:
            return _libln.ERROR_CLASSES[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
