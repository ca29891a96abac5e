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


def completion(
    shell: Shell = typer.Argument(
        ...,
        metavar="SHELL",
        show_default=False,
        help="The shell to complete for: bash, zsh or fish.",
    ),
) -> None:
    """Print the completion script for bash, zsh or fish.

    \b
    gadgetctl completion bash > ~/.local/share/bash-completion/completions/gadgetctl
    gadgetctl completion zsh > ~/.zfunc/_gadgetctl    # with ~/.zfunc on $fpath
    gadgetctl completion fish > ~/.config/fish/completions/gadgetctl.fish

    Driver, emulator, code, definition and element names are completed by asking gadgetctl
    as you type (`gadgetctl __complete`).
    """
    from gadgetctl.cli.completions import scripts

    emit(scripts()[shell.value])
