"""Entry point for `python -m ln_generate`."""

import sys

from .cli import main

sys.exit(main())
