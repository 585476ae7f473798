"""The language server under test: `python -m links_and_nodes.manager.frontends.lsp` started per test by a
real LSP client over stdio (pytest-lsp), with the settings and the position encodings
the test gives."""

from __future__ import annotations

import os
import sys
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import pytest_asyncio

try:
    import pytest_lsp
    from lsprotocol import types as lsp  # pygls brings it
    from pytest_lsp import LanguageClient, client_capabilities
except ImportError:
    # A test-only tool (requirements-dev.txt): CI's run from the checkout must have it; the
    # Debian package build, which has Debian's packages only, leaves these tests out.  (A
    # skip raised here would end the whole session, not just this folder.)
    if os.environ.get("CI") and not os.environ.get("LN_PACKAGE_TESTS"):
        raise
    collect_ignore_glob = ["test_*.py"]

Start = Callable[..., Awaitable["LanguageClient"]]


@pytest_asyncio.fixture
async def start_server() -> AsyncIterator[Start]:
    """start_server(settings, encodings) -> an initialised client (VS Code's capabilities,
    which offer no position encodings, or those of `encodings`); the encoding the server
    chose is its `position_encoding`.  Every server started is shut down after the test."""
    clients: list[LanguageClient] = []

    async def start(settings: dict[str, Any] | None = None,
                    encodings: list[str] | None = None) -> LanguageClient:
        client = pytest_lsp.make_test_lsp_client()
        _log_diagnostics(client)
        await client.start_io(sys.executable, "-m", "links_and_nodes.manager.frontends.lsp")
        clients.append(client)
        capabilities = client_capabilities("visual-studio-code")
        if encodings is not None:
            general = capabilities.general or lsp.GeneralClientCapabilities()
            general.position_encodings = encodings
            capabilities.general = general
        result = await client.initialize_session(lsp.InitializeParams(
            capabilities=capabilities, initialization_options=settings or {}))
        client.position_encoding = result.capabilities.position_encoding  # type: ignore[attr-defined]
        return client

    yield start
    for client in clients:
        await client.shutdown_session()
        await client.stop()


@pytest_asyncio.fixture
async def server(start_server: Start) -> LanguageClient:
    return await start_server()


def _log_diagnostics(client: LanguageClient) -> None:
    """Keep every publishDiagnostics in `client.published` (wait_for_notification sees
    only the next one, and a read publishes for several files at once)."""
    published: list[lsp.PublishDiagnosticsParams] = []
    handle = client.protocol._handle_notification

    def logged(method: str, params: Any) -> Any:
        if method == lsp.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS:
            published.append(params)
        return handle(method, params)

    client.protocol._handle_notification = logged  # type: ignore[method-assign]
    client.published = published  # type: ignore[attr-defined]
