"""The manager's default limits, a leaf module: the registry's Limits and service registry
take them from here, and so does `ln_manager --help`, which must not load the registry."""

TOPIC_LIMIT = 4096  # topics at a time
RING_MEMORY_LIMIT = 1 << 30  # bytes of one topic's ring
SERVICE_LIMIT = 4096  # services per manager
LOG_LINES = 20000  # client log lines the manager keeps, and the most one `log` answers
