"""The front ends: command table, console, CLI, CONTROL frames, scripting API, web UI."""
