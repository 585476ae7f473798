"""Hosts, routes and the topic streams between them, pull topics (docs/network.md, docs/pull.md)."""
