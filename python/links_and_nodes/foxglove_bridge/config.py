"""ln_foxglove's settings and its rules saying which topics and services become channels and
services of the Foxglove server.  Topic rules are ln_zenoh's specs
`PATTERN[,queued[=N]][,latest][,rate=HZ]`, service rules `PATTERN[,timeout=S]`
(zenoh_bridge/config.py parses both); the first rule whose pattern matches a name decides, and
without rules every topic and service is bridged with the defaults.  Exclusions win over rules.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .. import default_ports
from ..zenoh_bridge.config import ConfigError, ServiceRule, TopicRule, service_spec, topic_spec
from ..zenoh_bridge.wire import matches

DEFAULT_PORT = default_ports.FOXGLOVE_PORT
DEFAULT_HOST = "127.0.0.1"

__all__ = ["ConfigError", "FoxgloveConfig"]


@dataclass
class FoxgloveConfig:
    manager: str | None = None
    host: str = DEFAULT_HOST
    port: int = DEFAULT_PORT
    direct: bool = False  # the sdk on the port itself: foxglove.sdk.v1 only, no front
    origins: list[str] = field(default_factory=list)  # browser Origins allowed (none: any)
    topics: list[TopicRule] = field(default_factory=list)
    services: list[ServiceRule] = field(default_factory=list)
    exclude: list[str] = field(default_factory=list)  # topic and service name patterns
    offer_services: bool = True
    name: str = "ln_foxglove"  # client name at the manager
    md_dirs: list[str] = field(default_factory=list)
    poll: float = 1.0  # seconds between looks at the manager's topic and service lists
    verbose: bool = False

    def topic_rule(self, name: str) -> TopicRule | None:
        if self._excluded(name):
            return None
        if not self.topics:
            return TopicRule("*", "out")
        return next((r for r in self.topics if matches(name, r.pattern)), None)

    def service_rule(self, name: str) -> ServiceRule | None:
        if not self.offer_services or self._excluded(name):
            return None
        if not self.services:
            return ServiceRule("*", "out")
        return next((r for r in self.services if matches(name, r.pattern)), None)

    def _excluded(self, name: str) -> bool:
        return any(matches(name, pattern) for pattern in self.exclude)

    def check(self) -> None:
        if not 0 <= self.port <= 65535:
            raise ConfigError(f"port must be 0..65535, not {self.port}")
        if self.origins and self.direct:
            raise ConfigError("--origin needs the front: it does not go with --direct")
        if not self.poll > 0:
            raise ConfigError("poll must be a positive number of seconds")
        for rule in self.topics:
            if rule.remote is not None:
                raise ConfigError(f"{rule.pattern}: remote= is an ln_zenoh option")
            if not 2 <= rule.buffers <= 1024:
                raise ConfigError(f"{rule.pattern}: queued=N needs N in 2..1024")
            if rule.rate is not None and not rule.rate > 0:
                raise ConfigError(f"{rule.pattern}: rate must be a positive number")
        for srule in self.services:
            if srule.remote is not None:
                raise ConfigError(f"{srule.pattern}: remote= is an ln_zenoh option")
            if not srule.timeout > 0:
                raise ConfigError(f"{srule.pattern}: timeout must be positive")

    def add_topic_spec(self, spec: str) -> None:
        self.topics.append(topic_spec(spec, "out"))

    def add_service_spec(self, spec: str) -> None:
        self.services.append(service_spec(spec, "out"))

