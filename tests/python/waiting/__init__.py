"""Tests of waiting on many things at once: the waitset in C, C++ and Python, asyncio."""
