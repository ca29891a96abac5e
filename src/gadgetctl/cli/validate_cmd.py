"""`gadgetctl validate`."""

from __future__ import annotations

from pathlib import Path

import typer

from gadgetctl.cli.options import COLOR_OPTION, ColorMode, DiagnosticFormat, emit, use_color


def register(app: typer.Typer) -> None:
    app.command(name="validate")(validate)


def validate(
    paths: list[Path] = typer.Argument(..., help="Files or directories (searched for *.jdef and *.jconf).", show_default=False),
    fmt: DiagnosticFormat = typer.Option(DiagnosticFormat.text, "--format", "-f", help="Output format."),
    strict: bool = typer.Option(False, "--strict", help="Exit 1 on warnings too."),
    max_size: int = typer.Option(16 * 1024 * 1024, "--max-size", help="Largest file read, in bytes.", min=1),
    hints: bool = typer.Option(True, "--hints/--no-hints", help="Show a hint under findings that have one (text format)."),
    color: ColorMode = COLOR_OPTION,
) -> None:
    """Check JCCL definition (.jdef) and configuration (.jconf) files.

    Exit status: 0 clean (warnings allowed unless --strict), 1 errors found, 2 usage or tool error.
    """
    from gadgetctl.diagnostics import exit_code_for
    from gadgetctl.report import render
    from gadgetctl.validate import ValidateOptions, validate_paths

    result = validate_paths(paths, ValidateOptions(max_size=max_size))
    emit(render(fmt.value, result.diagnostics, files_checked=len(result.files),
                color=use_color(color), hints=hints))
    raise typer.Exit(exit_code_for(result.diagnostics, strict=strict))
