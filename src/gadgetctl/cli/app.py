"""The typer application: the root command and the registration of every sub-command."""

from __future__ import annotations

import typer

from gadgetctl import __version__

HELP = (
    "Configuration and diagnostics toolkit for VR input devices (VR Juggler / Gadgeteer): "
    "validate JCCL .jdef/.jconf files, inspect definitions and configurations, load driver "
    "plug-ins and monitor live devices."
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"gadgetctl {__version__}")
        raise typer.Exit()


def build_app() -> typer.Typer:
    app = typer.Typer(
        name="gadgetctl",
        help=HELP,
        no_args_is_help=True,
        add_completion=False,
        pretty_exceptions_enable=False,
        rich_markup_mode=None,
        context_settings={"help_option_names": ["-h", "--help"]},
    )

    @app.callback()
    def root(
        version: bool = typer.Option(False, "--version", "-V", callback=_version, is_eager=True,
                                     help="Print the version and exit."),
    ) -> None:
        """Configuration and diagnostics toolkit for VR input devices."""

    from gadgetctl.cli import commands

    commands.register_all(app)
    return app
