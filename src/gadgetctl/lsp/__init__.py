"""The JCCL language server (`gadgetctl lsp`): validate's findings, completion, hover,
navigation and fixes for .jconf and .jdef files in any editor speaking the Language Server
Protocol.

Everything here runs on the library core: diagnostics are :func:`gadgetctl.validate.validate_paths`
over the editor's unsaved texts (:func:`gadgetctl.jccl.xmlload.unsaved_texts`), the model
behind completion, hover and navigation is the configuration loader and type index the
checks use. The feature modules work on plain text offsets; only :mod:`.server` knows pygls
and lsprotocol (the ``lsp`` extra).
"""

from __future__ import annotations

EXTRA_HINT = (
    "gadgetctl lsp needs the lsp extra: pip install 'gadgetctl[lsp]' (pygls >= 2 and lsprotocol)"
)


def available() -> bool:
    """Whether pygls (2 or later) and lsprotocol can be imported."""
    try:
        import lsprotocol.types  # noqa: F401
        from pygls.lsp.server import LanguageServer  # noqa: F401  (pygls 2's module)
    except ImportError:
        return False
    return True
