"""`gadgetctl explain`."""

from __future__ import annotations

import json

import typer

from gadgetctl.cli.options import DataFormat, emit


def register(app: typer.Typer) -> None:
    app.command(name="explain")(explain)


def explain(
    code: str = typer.Argument(
        None,
        metavar="CODE",
        help="A diagnostic code such as XML002; all codes when left out.",
        show_default=False,
    ),
    fmt: DataFormat = typer.Option(DataFormat.text, "--format", "-f", help="Output format."),
) -> None:
    """Describe a diagnostic code, with an example and how to fix it."""
    from gadgetctl.diagnostics import all_codes
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.suggest import with_suggestion

    codes = all_codes()
    if code is None:
        entries = sorted(codes.values(), key=lambda c: c.code)
        if fmt is DataFormat.json:
            emit(json.dumps([_as_dict(c) for c in entries], indent=2))
        else:
            emit(
                "\n".join(
                    f"{c.code:<8} {c.severity.value:<8} {c.category.value:<11} {c.title}"
                    for c in entries
                )
            )
        return
    entry = codes.get(code.upper())
    if entry is None:
        raise GadgetctlError(
            with_suggestion(
                f"unknown diagnostic code {code!r}", code.upper(), codes, cutoff=0.5, quote=str
            )
        )
    if fmt is DataFormat.json:
        emit(json.dumps(_as_dict(entry), indent=2))
        return
    lines = [
        f"{entry.code}: {entry.title}",
        f"category: {entry.category.value}, default severity: {entry.severity.value}",
        "",
        entry.description,
    ]
    if entry.example:
        lines += ["", "Example:", *("    " + line for line in entry.example.splitlines())]
    if entry.fix:
        lines += ["", "How to fix: " + entry.fix]
    emit("\n".join(lines))


def _as_dict(entry) -> dict:
    return {
        "code": entry.code,
        "category": entry.category.value,
        "severity": entry.severity.value,
        "title": entry.title,
        "description": entry.description,
        "example": entry.example,
        "fix": entry.fix,
    }
