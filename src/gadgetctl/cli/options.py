"""Options and small helpers shared by several commands."""

from __future__ import annotations

import typer

from gadgetctl.cli.choices import (
    CheckLevel,
    ColorMode,
    DataFormat,
    DiagnosticFormat,
    emit,
    use_color,
)

__all__ = [
    "BUNDLED_OPTION",
    "COLOR_OPTION",
    "DEFINITIONS_OPTION",
    "CheckLevel",
    "ColorMode",
    "DataFormat",
    "DiagnosticFormat",
    "emit",
    "use_color",
]

COLOR_OPTION = typer.Option(
    ColorMode.auto, "--color", help="Colour the output: auto (only on a terminal), always or never."
)


DEFINITIONS_OPTION = typer.Option(
    [],
    "--definitions",
    "-d",
    metavar="DIR",
    help="Add a directory to the definition search path (after the bundled set, VJ_BASE_DIR and JCCL_DEFINITION_PATH). Repeatable.",
)
BUNDLED_OPTION = typer.Option(
    True, "--bundled/--no-bundled", help="Use gadgetctl's bundled standard definitions."
)
