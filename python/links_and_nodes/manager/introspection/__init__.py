"""Live introspection: topic echo/hz/bw, md show, service call (docs/introspection.md)."""
