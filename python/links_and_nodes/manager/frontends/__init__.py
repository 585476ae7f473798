"""The front ends: console, CLI, CONTROL frames, web UI, and their share of the command
table (commands/); the table itself and the scripting client are in tools/."""
