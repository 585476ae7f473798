"""The one Python home of transport names: how a topic's samples travel between hosts
(forwarding by the daemons over UDP or TCP), within one host (shared memory) and how pull
topics are served (NDN over UDP), as the configuration, the client API, the manager's views
and the daemon wire name them."""

from __future__ import annotations

UDP = "udp"
TCP = "tcp"
SHM = "shm"  # within one host: the ring in shared memory, no transport between hosts
FORWARD = (UDP, TCP)  # what `transport:` in a topics section and a subscriber may ask for
DEFAULT_FORWARD = UDP  # when nobody asks

NDN_UDP = "ndn-udp"  # `pull:ndn-udp`: NDN Interest/Data over UDP
PULL_OFF = "off"  # `pull:off`: the topics the line matches are not served
PULL = (NDN_UDP, PULL_OFF)  # what `pull:` may say


def asked(flags: int, *, udp_flag: int, tcp_flag: int) -> str | None:
    """The forwarding transport subscribe flags ask for (TCP wins when both are set), or
    None when they ask for none."""
    if flags & tcp_flag:
        return TCP
    return UDP if flags & udp_flag else None
