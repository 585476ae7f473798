"""Parameter blocks: tools, console and CLI words, scripting methods (docs/parameters.md)."""
