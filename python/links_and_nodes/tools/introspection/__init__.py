"""The client side of live introspection (docs/introspection.md): value decoding, request
text, rate statistics, the libln subscriber and service caller, the commands (commands.py)
and their text (views.py).  Importing the package or views.py loads neither ln_generate nor
libln: the command table names these commands without running them."""

DEFAULT_TIMEOUT = 10.0  # seconds a service call may take
