"""`gadgetctl validate`."""

from __future__ import annotations

from pathlib import Path

import typer

from gadgetctl.cli.exiting import finish
from gadgetctl.cli.options import (
    BUNDLED_OPTION,
    COLOR_OPTION,
    DEFINITIONS_OPTION,
    CheckLevel,
    ColorMode,
    DiagnosticFormat,
    emit,
    use_color,
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
    fmt: DiagnosticFormat = typer.Option(
        DiagnosticFormat.text, "--format", "-f", help="Output format."
    ),
    strict: bool = typer.Option(False, "--strict", help="Exit 1 on warnings too."),
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
    together: bool = typer.Option(
        False,
        "--together",
        help="Treat all configuration files as one configuration, as VR Juggler does with several files on its command line (pointer checks span them all).",
    ),
    level: CheckLevel = typer.Option(
        CheckLevel.full,
        "--level",
        help="How far to check: xml (well-formedness, encoding, format markers), schema, definitions, or full (configuration semantics too).",
    ),
    max_size: int = typer.Option(
        16 * 1024 * 1024, "--max-size", help="Largest file read, in bytes.", min=1
    ),
    hints: bool = typer.Option(
        True, "--hints/--no-hints", help="Show a hint under findings that have one (text format)."
    ),
    color: ColorMode = COLOR_OPTION,
) -> None:
    """Check JCCL definition (.jdef) and configuration (.jconf) files.

    Exit status: 0 clean (warnings allowed unless --strict), 1 errors found, 2 usage or tool error.
    """
    from gadgetctl.cli import exiting
    from gadgetctl.diagnostics import exit_code_for
    from gadgetctl.perf import retain_until_exit
    from gadgetctl.report import render
    from gadgetctl.validate import ValidateOptions, validate_paths

    if exiting.own_process:  # validate ends with finish(): what it builds need not be freed
        retain_until_exit()
    options = ValidateOptions(
        max_size=max_size,
        level=level.value,
        bundled=bundled,
        definition_dirs=list(definitions),
        together=together,
    )
    result = validate_paths(paths, options)
    emit(
        render(
            fmt.value,
            result.diagnostics,
            files_checked=len(result.files),
            color=use_color(color),
            hints=hints,
        )
    )
    finish(exit_code_for(result.diagnostics, strict=strict))
