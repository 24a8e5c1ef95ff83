"""`st lsp`: a language server for ST (docs/editors.md).

project.py decides which files a document is checked with, analysis.py checks them (the
compiler's parser and checker, re-parsing only what changed), index.py reads every name's
definition and references off the checked trees, features.py answers the editor's questions
(hover, definition, references, symbols, completion, rename, semantic tokens), server.py speaks
LSP over stdio with pygls.
"""
