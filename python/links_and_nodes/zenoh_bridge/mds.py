"""Message definitions across the bridge: the queryable that serves the text of the mds this
bridge publishes (`P/md/<md name>`, with what they import, as mcap_format.md_schema_text gives
it), and the resolver that finds the Python class for an md a remote bridge names, checking its
layout hash: the local md if there is one, else the remote's text built with
mcap_format.schema_message_class."""

from __future__ import annotations

import threading
from typing import Any

from .. import md_loader
from ..mcap_format import md_schema_text, schema_message_class
from .wire import md_key, name_in

FETCH_TIMEOUT = 5.0  # seconds to wait for a remote md's text


class LayoutMismatch(Exception):
    """The md's layout here differs from the remote's: the text names both hashes."""


class MdUnavailable(Exception):
    """The md is not known here and the remote bridge did not give its text."""


class MdServer:
    """Answers `P/md/**` for the mds in `served` (and what they import)."""

    def __init__(self, session: Any, prefix: str) -> None:
        self.prefix = prefix
        self.served: set[str] = set()
        self._texts: dict[str, bytes] = {}
        self._lock = threading.Lock()
        self._queryable = session.declare_queryable(md_key(prefix, "**"), self._on_query)

    def serve(self, md_name: str) -> None:
        text = md_schema_text(md_name)
        with self._lock:
            self._texts[md_name] = text
            self.served.add(md_name)

    def _on_query(self, query: Any) -> None:
        name = name_in(str(query.key_expr), self.prefix, "md")
        with self._lock:
            text = self._texts.get(name or "")
        if text is None:
            query.reply_err(f"md {name!r} is not bridged by {self.prefix}".encode())
        else:
            query.reply(query.key_expr, text)

    def close(self) -> None:
        self._queryable.undeclare()


class MdResolver:
    """The class of (md name, layout hash) as a remote bridge names them."""

    def __init__(self, session: Any) -> None:
        self.session = session
        self._remote: dict[tuple[str, int], Any] = {}
        self._lock = threading.Lock()

    def resolve(self, md_name: str, layout_hash: int, remote: str) -> Any:
        """LayoutMismatch if the md here (or the text the remote gives) has another layout hash;
        MdUnavailable if it is not known here and the remote does not give its text."""
        try:
            cls = md_loader.message_class(md_name)
        except Exception:  # noqa: BLE001 - MdError, a missing file: not known here
            cls = None
        if cls is not None:
            if cls.LAYOUT_HASH != layout_hash:
                raise LayoutMismatch(
                    f"layout hash mismatch for md '{md_name}': remote {remote} has "
                    f"0x{layout_hash:016x}, here it is 0x{cls.LAYOUT_HASH:016x}")
            return cls
        with self._lock:
            cls = self._remote.get((md_name, layout_hash))
        if cls is not None:
            return cls
        text = self.fetch(md_name, remote)
        try:
            cls = schema_message_class(md_name, text)
        except Exception as exc:  # noqa: BLE001 - a text ln_generate refuses
            raise MdUnavailable(f"the text of md '{md_name}' from {remote} does not build: "
                                f"{exc}") from None
        if cls.LAYOUT_HASH != layout_hash:
            raise LayoutMismatch(
                f"layout hash mismatch for md '{md_name}': samples from {remote} say "
                f"0x{layout_hash:016x}, the md text it serves gives 0x{cls.LAYOUT_HASH:016x}")
        with self._lock:
            self._remote[(md_name, layout_hash)] = cls
        # Ports look their md up by name (md_loader.message_class): an md not known here is
        # added to its cache under that name, so publish/get_service_provider find it.
        with md_loader._lock:
            md_loader._classes.setdefault(md_name, cls)
        return cls

    def fetch(self, md_name: str, remote: str) -> bytes:
        errors = []
        for reply in self.session.get(md_key(remote, md_name), timeout=FETCH_TIMEOUT):
            if reply.ok is not None:
                return bytes(reply.ok.payload.to_bytes())
            errors.append(reply.err.payload.to_bytes().decode(errors="replace"))
        why = "; ".join(errors) or f"no answer within {FETCH_TIMEOUT:g} s"
        raise MdUnavailable(f"md '{md_name}' is not known here and {remote} did not give its "
                            f"text: {why}")
