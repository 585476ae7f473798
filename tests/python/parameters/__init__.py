"""Tests of parameter blocks (docs/parameters.md)."""
