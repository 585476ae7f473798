"""The client side of live introspection (docs/introspection.md): value decoding, request
text, rate statistics, the libln subscriber and service caller, the commands (commands.py)
and their text (views.py)."""
