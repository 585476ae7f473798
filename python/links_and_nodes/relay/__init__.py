"""ln_relay: a userspace relay between two hosts' endpoints that injects loss, delay,
jitter, duplication and reordering into UDP and the application-visible equivalent into
TCP, for tests and benchmarks of host-to-host forwarding where netem is not available
(docs/relay.md).  Relay and FaultSpec are the library; cli.py is the command."""

from .addresses import Address, RelayError, format_address, parse_address
from .core import Link, Relay
from .faults import FaultSpec
from .stats import DirectionStats, LinkStats

__all__ = ["Address", "DirectionStats", "FaultSpec", "Link", "LinkStats", "Relay",
           "RelayError", "format_address", "parse_address"]
