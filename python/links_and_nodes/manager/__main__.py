"""`python -m links_and_nodes.manager`: the same as the `ln_manager` console script."""

import sys

from .frontends.cli import main

sys.exit(main())
