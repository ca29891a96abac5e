"""`gadgetctl --help` answered without the CLI framework (issue 27 goal 4).

Importing typer (and the Click it carries) is most of the cost of ``gadgetctl --help``,
so the root help is kept here as text rendered by typer itself (:func:`render`) and
printed by :func:`answer` when it is exactly what typer would print: ``--help`` or ``-h``
alone, on a terminal at least :data:`COLUMNS` wide or no terminal (Click wraps its help to
at most 78 columns). ``tests/test_cli_roothelp.py`` fails when the text is stale; ``make
completions`` (or ``python -m gadgetctl.cli.roothelp``) writes it again.
"""

from __future__ import annotations

import sys

from gadgetctl.cli.roothelp_text import TEXT

#: Terminal columns from which Click's help is as wide as it gets.
COLUMNS = 80


def answer(args: list[str]) -> bool:
    """Print the root help and return True when ``args`` ask for it (and the text kept is
    what typer would print); False: let typer answer."""
    if args not in (["--help"], ["-h"]):
        return False
    import shutil

    if shutil.get_terminal_size().columns < COLUMNS:
        return False
    sys.stdout.write(TEXT)
    sys.stdout.flush()
    return True


def render() -> str:
    """The root help as typer prints it on a terminal of :data:`COLUMNS` columns."""
    import contextlib
    import io
    import os

    from gadgetctl.cli.app import build_app

    saved = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = str(COLUMNS)
    out = io.StringIO()
    try:
        with contextlib.redirect_stdout(out):
            build_app()(args=["--help"], prog_name="gadgetctl", standalone_mode=False)
    finally:
        if saved is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = saved
    return out.getvalue()


def source(text: str) -> str:
    """The module that keeps ``text`` (roothelp_text.py), formatted as ruff formats it."""
    import json

    return (
        '"""The text of `gadgetctl --help`, written by `python -m gadgetctl.cli.roothelp`'
        ' (make completions); do not edit."""\n\nTEXT = (\n'
        + "".join(f"    {json.dumps(line)}\n" for line in text.splitlines(keepends=True))
        + ")\n"
    )


if __name__ == "__main__":
    from pathlib import Path

    target = Path(__file__).with_name("roothelp_text.py")
    target.write_text(source(render()), encoding="utf-8")
    print(target)
