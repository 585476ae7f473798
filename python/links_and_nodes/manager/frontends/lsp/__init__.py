"""`ln_lsp`, the language server for `.lnc` configurations and message definitions
(docs/editors.md): the project's own configuration reader and md parser behind the LSP
features (diagnostics, hover, definitions, references, completion, outline)."""
