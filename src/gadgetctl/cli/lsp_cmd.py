"""`gadgetctl lsp`: the JCCL language server (the work is in gadgetctl.lsp)."""

from __future__ import annotations

from pathlib import Path

import typer

from gadgetctl.cli.options import BUNDLED_OPTION, DEFINITIONS_OPTION

EDITORS = """Point your editor's LSP client at `gadgetctl lsp` for *.jconf and *.jdef files:

\b
  VS Code  a generic LSP client extension: command gadgetctl, args ["lsp"]
  Neovim   vim.lsp.start with name "gadgetctl" and cmd "gadgetctl", "lsp" (docs/lsp.md)
  Helix    [language-server.gadgetctl] command = "gadgetctl", args = ["lsp"]
  Emacs    (add-to-list 'eglot-server-programs '((nxml-mode) "gadgetctl" "lsp"))

Full set-up: docs/lsp.md. Needs the lsp extra: pip install 'gadgetctl[lsp]'."""


def register(app: typer.Typer) -> None:
    app.command(
        name="lsp", help=f"Run the JCCL language server (standard input/output).\n\n{EDITORS}"
    )(lsp)


def lsp(
    tcp: int | None = typer.Option(
        None,
        "--tcp",
        metavar="PORT",
        min=0,
        max=65535,
        help="Serve one client on 127.0.0.1:PORT instead of standard input/output (0: a port the OS picks, said on standard error).",
    ),
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
) -> None:
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.lsp import EXTRA_HINT, available

    if not available():
        raise GadgetctlError(EXTRA_HINT)
    for directory in definitions:
        if not directory.is_dir():
            raise GadgetctlError(f"--definitions {directory}: no such directory")
    from gadgetctl.lsp.analysis import EngineOptions
    from gadgetctl.lsp.server import serve

    serve(tcp_port=tcp, options=EngineOptions(definition_dirs=list(definitions), bundled=bundled))
