"""`gadgetctl demo`: the main job on the bundled defaults (what `make demo` runs)."""

from __future__ import annotations

import typer

from gadgetctl.cli.options import ColorMode, emit, use_color


def register(app: typer.Typer) -> None:
    app.command(name="demo")(demo)


def demo() -> None:
    """Validate the bundled definitions and example configurations and print the report."""
    from gadgetctl.diagnostics import exit_code_for
    from gadgetctl.report import render
    from gadgetctl.resources import definitions_dir, drivers_dir, examples_dir
    from gadgetctl.validate import validate_paths

    paths = [p for p in (definitions_dir(), examples_dir(), drivers_dir()) if p.is_dir()]
    result = validate_paths(paths)
    emit(f"Validating the bundled definitions, drivers and examples ({len(result.files)} files)")
    emit(render("text", result.diagnostics, files_checked=len(result.files), color=use_color(ColorMode.auto)))
    raise typer.Exit(exit_code_for(result.diagnostics))
