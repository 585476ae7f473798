"""End-to-end tests of services between Python and C providers and callers."""
