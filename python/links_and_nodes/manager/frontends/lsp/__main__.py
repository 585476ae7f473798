"""`python -m links_and_nodes.manager.frontends.lsp`: the language server on stdio (as
`ln_lsp`)."""

import sys

from links_and_nodes.manager.frontends.lsp.cli import main

sys.exit(main())
