"""The typer application: the root command and the registration of every sub-command."""

from __future__ import annotations

import typer
from typer.core import TyperArgument, TyperGroup

from gadgetctl import __version__

HELP = (
    "Configuration and diagnostics toolkit for VR input devices (VR Juggler / Gadgeteer): "
    "validate JCCL .jdef/.jconf files, inspect definitions and configurations, load driver "
    "plug-ins and monitor live devices."
)


class _UsageArgument(TyperArgument):
    """An argument shown in usage lines by its metavar alone (`PATHS...`, `[CODE]`), where
    typer would wrap a required one in braces (`{PATHS...}`)."""

    def make_metavar(self, ctx, *, usage: bool = False) -> str:
        if usage and self.required and self.metavar is not None:
            return self.metavar
        return super().make_metavar(ctx, usage=usage)


class RootGroup(TyperGroup):
    """The root command: every argument below it gets the plain usage form."""

    def __init__(self, **attrs) -> None:
        super().__init__(**attrs)
        pending = list(self.commands.values())
        while pending:
            command = pending.pop()
            pending.extend(getattr(command, "commands", {}).values())
            for param in command.params:
                if type(param) is TyperArgument:
                    param.__class__ = _UsageArgument


def _version(value: bool) -> None:
    if value:
        typer.echo(f"gadgetctl {__version__}")
        raise typer.Exit()


def build_app(command: str | None = None) -> typer.Typer:
    """The application with every command, or with only ``command`` (a name in
    :data:`gadgetctl.cli.commands.COMMANDS`) when the command line names it."""
    app = typer.Typer(
        name="gadgetctl",
        cls=RootGroup,
        help=HELP,
        no_args_is_help=True,
        add_completion=False,
        pretty_exceptions_enable=False,
        rich_markup_mode=None,
        context_settings={"help_option_names": ["-h", "--help"]},
    )

    @app.callback()
    def root(
        version: bool = typer.Option(
            False,
            "--version",
            "-V",
            callback=_version,
            is_eager=True,
            help="Print the version and exit.",
        ),
    ) -> None:
        """Configuration and diagnostics toolkit for VR input devices."""

    from gadgetctl.cli import commands

    commands.register_all(app, command)
    return app
