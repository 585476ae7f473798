"""Parameter blocks in the manager: the `param ...` entries of the command table
(docs/parameters.md); the client side they run is tools/parameters/."""
