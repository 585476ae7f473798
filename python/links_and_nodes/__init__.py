"""links_and_nodes: Python bindings of libln, the links_and_nodes client library.

Importing the package does not load libln.  The library is loaded (and its version
checked) the first time something that needs it is used, e.g. one of the exception
classes generated from libln's error table: ``ln.LnTimeoutError`` is the class for
``LN_ETIMEOUT``; the rule is "Ln" + table name without its leading E, capitalised,
+ "Error".  All of them derive from ``ln.LnError``.
"""

from typing import Any

from .errors import LibraryNotFoundError, LnError

__version__ = "0.1.0"

__all__ = ["LibraryNotFoundError", "LnError", "__version__"]


def __getattr__(name: str) -> Any:
    # Generated exception classes come from the C table, so they exist only once libln
    # is loaded; looking one up is what loads it.
    if name.startswith("Ln") and name.endswith("Error"):
        from . import _libln

        if name in _libln.ERROR_CLASSES:
            return _libln.ERROR_CLASSES[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
