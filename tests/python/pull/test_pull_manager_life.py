"""The manager's side of a pull topic's life (manager/network/pull.py): a daemon's refusal (the
port taken by another program) shown with its text in `pull` and `network` and retried until
the port is free; a detached manager leaving the topic served, and the next manager of the
instance removing what its configuration no longer serves."""

from __future__ import annotations

import socket

from polling import wait_for

from . import ndn_wire as w
from .conftest import PullLab, udp_port_free

TOPIC = "arm.state"


def test_refusal_shown_and_retried_until_the_port_is_free(pulllab: PullLab) -> None:
    squatter = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    squatter.bind(("127.0.0.1", pulllab.port))
    try:
        pulllab.serve()
        pulllab.publisher(TOPIC, 2000)
        listed = wait_for(lambda: [t for t in pulllab.pull_topics() if t["error"]],
                          "the daemon's refusal in the pull listing")
        error = listed[0]["error"]  # type: ignore[index]
        assert f"127.0.0.1:{pulllab.port}" in error, error
        (host,) = pulllab.network()["pull"]
        assert host["topics"][0]["error"] == error
        assert host["topics"][0]["topic"] == TOPIC and host["topics"][0]["data"] == 0
        assert "127.0.0.1" in pulllab.cli("pull").stdout
    finally:
        squatter.close()
    pulllab.served(TOPIC)  # retried by the manager once the port is free
    assert [t["error"] for t in pulllab.pull_topics()] == [""]


def test_detach_leaves_it_served_and_the_next_manager_cleans_up(pulllab: PullLab) -> None:
    pulllab.serve()
    pulllab.publisher(TOPIC, 2000)
    pulllab.served(TOPIC)
    with pulllab.lab.connect() as mgr:
        mgr.command("detach")
    pulllab.lab.managers[-1].wait(timeout=60)
    sync = w.interest(w.name_value(pulllab.uri(TOPIC), None, ("sync",)), nonce=9,
                      can_be_prefix=True, must_be_fresh=True)
    reply = pulllab.ask(sync)
    assert reply is not None and w.decode_data(reply).name.startswith(
        w.name_value(pulllab.uri(TOPIC), None, ("sync",)))
    # the next manager's configuration serves nothing: it removes what it found
    pulllab.start("")
    wait_for(lambda: udp_port_free(pulllab.port), "the leftover pull topic removed")
