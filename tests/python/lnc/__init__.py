"""Tests of the `.lnc` configuration reader (links_and_nodes.manager.config)."""
