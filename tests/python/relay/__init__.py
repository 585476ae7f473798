"""Tests of ln_relay (links_and_nodes.relay): the fault rules, UDP and TCP links, the command."""
