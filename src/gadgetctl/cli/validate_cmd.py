"""`gadgetctl validate`."""

from __future__ import annotations

from pathlib import Path

import typer

from gadgetctl.cli.options import (
    BUNDLED_OPTION,
    COLOR_OPTION,
    DEFINITIONS_OPTION,
    CheckLevel,
    ColorMode,
    DiagnosticFormat,
)
from gadgetctl.cli.validate_run import (
    DEFAULT_FORMAT,
    DEFAULT_LEVEL,
    DEFAULT_MAX_SIZE,
    run_validate,
)


def register(app: typer.Typer) -> None:
    app.command(name="validate")(validate)


def validate(
    paths: list[Path] = typer.Argument(
        ...,
        metavar="PATHS...",
        help="Files or directories (searched for *.jdef and *.jconf).",
        show_default=False,
    ),
    fmt: DiagnosticFormat = typer.Option(DEFAULT_FORMAT, "--format", "-f", help="Output format."),
    strict: bool = typer.Option(False, "--strict", help="Exit 1 on warnings too."),
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
    together: bool = typer.Option(
        False,
        "--together",
        help="Treat all configuration files as one configuration, as VR Juggler does with several files on its command line (pointer checks span them all).",
    ),
    level: CheckLevel = typer.Option(
        DEFAULT_LEVEL,
        "--level",
        help="How far to check: xml (well-formedness, encoding, format markers), schema, definitions, or full (configuration semantics too).",
    ),
    max_size: int = typer.Option(
        DEFAULT_MAX_SIZE, "--max-size", help="Largest file read, in bytes.", min=1
    ),
    hints: bool = typer.Option(
        True, "--hints/--no-hints", help="Show a hint under findings that have one (text format)."
    ),
    color: ColorMode = COLOR_OPTION,
) -> None:
    """Check JCCL definition (.jdef) and configuration (.jconf) files.

    Exit status: 0 clean (warnings allowed unless --strict), 1 errors found, 2 usage or tool error.
    """
    run_validate(paths, fmt, strict, definitions, bundled, together, level, max_size, hints, color)
