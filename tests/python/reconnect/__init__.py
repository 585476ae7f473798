"""End-to-end tests of clients that outlive their manager (tests/python/reconnect)."""
