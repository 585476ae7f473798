"""Topic loggers in the daemons and their commands (docs/logging.md)."""
