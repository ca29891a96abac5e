"""What `gadgetctl validate` does once its command line is read, by typer
(:mod:`gadgetctl.cli.validate_cmd`) or without it (:mod:`gadgetctl.cli.validate_fast`)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from gadgetctl.cli.choices import CheckLevel, ColorMode, DiagnosticFormat, emit, use_color

#: The options' defaults, shared by both readings of the command line.
DEFAULT_FORMAT = DiagnosticFormat.text
DEFAULT_LEVEL = CheckLevel.full
DEFAULT_MAX_SIZE = 16 * 1024 * 1024
DEFAULT_COLOR = ColorMode.auto


def run_validate(
    paths: Sequence[Path],
    fmt: DiagnosticFormat = DEFAULT_FORMAT,
    strict: bool = False,
    definitions: Sequence[Path] = (),
    bundled: bool = True,
    together: bool = False,
    level: CheckLevel = DEFAULT_LEVEL,
    max_size: int = DEFAULT_MAX_SIZE,
    hints: bool = True,
    color: ColorMode = DEFAULT_COLOR,
) -> None:
    """Validate ``paths``, print the report and end the command (see
    :func:`gadgetctl.cli.exiting.finish`) with the exit status of its findings."""
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
    exiting.finish(exit_code_for(result.diagnostics, strict=strict))
