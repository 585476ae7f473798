"""Tests of the manager's web UI (docs/webui.md): its server, security and the page in Chromium."""
