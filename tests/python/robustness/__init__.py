"""Crash injection (tests/python/robustness): a synthetic system under a real manager and
daemon whose components are SIGKILLed at random; see docs/robustness.md
("Crash injection")."""
