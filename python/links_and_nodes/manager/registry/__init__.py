"""What the manager knows: clients, topics, services, their shared memory, and the server clients talk to (docs/protocol.md)."""
