"""Processes: the scheduler and the manager's link to each host's ln_daemon (docs/process_management.md, docs/daemon.md)."""
