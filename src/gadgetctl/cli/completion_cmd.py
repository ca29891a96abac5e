"""`gadgetctl completion SHELL`: print a shell-completion script."""

from __future__ import annotations

from enum import StrEnum

import typer

from gadgetctl.cli.options import emit


class Shell(StrEnum):
    bash = "bash"
    zsh = "zsh"
    fish = "fish"


def register(app: typer.Typer) -> None:
    app.command(name="completion")(completion)


def completion(shell: Shell = typer.Argument(..., help="The shell to complete for.")) -> None:
    """Print a completion script: e.g. `gadgetctl completion bash > ~/.local/share/bash-completion/completions/gadgetctl`."""
    from gadgetctl.cli.completions import scripts

    emit(scripts()[shell.value])
