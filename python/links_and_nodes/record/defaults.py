"""The choices and defaults of a recording, a leaf module: encodings.py and recorder.py take
them from here, and so does `ln_record --help`, which must not load the writer (numpy,
ln_generate, libln)."""

ENCODINGS = ("ros2", "json", "ln")
DEFAULT_ENCODING = "ros2"
MAX_BUFFERS = 1024  # libln's limit per port
DEFAULT_BUFFER_MEMORY = 64 << 20  # bytes of queued samples per topic, by default
