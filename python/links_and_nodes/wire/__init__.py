"""Wire schemas and the codecs generated from them: schema.py parses a *.schema file (one
per protocol: daemon.schema for manager <-> ln_daemon, client.schema for client <->
manager), gen_cpp.py / gen_c.py write C++ and C codecs at build time, codec.py is the
Python codec built from a schema at import time.  Importing this package loads no libln."""
