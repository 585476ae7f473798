"""The client side of parameter blocks (docs/parameters.md): the value rule (values.py),
the blocks and their calls (blocks.py), the `param ...` commands and their text
(commands.py)."""
