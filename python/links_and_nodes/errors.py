"""Exception base classes of links_and_nodes and the rule that turns libln's error table
into one exception class per entry.  A leaf module: it imports nothing of ours, so it
works (and can be tested) without the C library."""

from collections.abc import Iterable

__all__ = ["LibraryNotFoundError", "LnError", "class_name", "make_error_classes"]


class LibraryNotFoundError(ImportError):
    """libln could not be loaded from any of the places the bindings look."""


class LnError(Exception):
    """An error reported by libln.

    ``code`` is the negative LN_E* value, ``name`` its table name (e.g. "ETIMEOUT") and
    ``text`` the table's message; ``detail`` is optional context from the failing call.
    """

    code: int = 0
    name: str = ""
    text: str = ""

    def __init__(self, detail: str | None = None) -> None:
        # args holds only what the constructor takes, so instances pickle and copy.
        super().__init__(*(() if detail is None else (detail,)))
        self.detail = detail

    def __str__(self) -> str:
        message = f"{self.name}: {self.text}" if self.name else "libln error"
        return f"{message}: {self.detail}" if self.detail else message


def class_name(table_name: str) -> str:
    """Python class name of a table entry: "ETIMEOUT" -> "LnTimeoutError"."""
    return "Ln" + table_name.removeprefix("E").capitalize() + "Error"


def make_error_classes(table: Iterable[tuple[int, str, str]]) -> dict[int, type[LnError]]:
    """One LnError subclass per (code, name, text) entry, keyed by code."""
    classes: dict[int, type[LnError]] = {}
    for code, name, text in table:
        cls = type(class_name(name), (LnError,), {
            "code": code, "name": name, "text": text,
            "__doc__": f"LN_{name} ({code}): {text}.",
            "__module__": "links_and_nodes",
        })
        classes[code] = cls
    return classes
