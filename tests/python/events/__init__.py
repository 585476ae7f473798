"""End-to-end tests of events between Python, C and C++ handlers and callers."""
