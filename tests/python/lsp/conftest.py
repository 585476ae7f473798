"""The language server under test: `python -m links_and_nodes.manager.frontends.lsp` started per test by a
real LSP client over stdio (pytest-lsp), with the settings the test gives."""

from __future__ import annotations

import sys
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import pytest
import pytest_asyncio

pytest_lsp = pytest.importorskip("pytest_lsp")
from lsprotocol import types as lsp  # noqa: E402  (after the skip: pygls brings it)
from pytest_lsp import LanguageClient, client_capabilities  # noqa: E402

Start = Callable[..., Awaitable[LanguageClient]]


@pytest_asyncio.fixture
async def start_server() -> AsyncIterator[Start]:
    """start_server(settings) -> an initialised client; every server started is shut
    down after the test."""
    clients: list[LanguageClient] = []

    async def start(settings: dict[str, Any] | None = None) -> LanguageClient:
        client = pytest_lsp.make_test_lsp_client()
        _log_diagnostics(client)
        await client.start_io(sys.executable, "-m", "links_and_nodes.manager.frontends.lsp")
        clients.append(client)
        await client.initialize_session(lsp.InitializeParams(
            capabilities=client_capabilities("visual-studio-code"),
            initialization_options=settings or {}))
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
