"""`gadgetctl validate` read without the CLI framework (issue 27 goal 4).

Importing typer and building the command costs a validate process about a fifth of its
time. A command line made only of paths and the command's own options, each written out
whole (``--format json``, ``--format=json``, ``-f json``), is read here into what typer
would pass to :func:`gadgetctl.cli.validate_run.run_validate`; anything else (``--help``,
an unknown or abbreviated option, a bad value, a value or path that starts with ``-``,
``--``, shell completion; any command line on Windows, where Click expands wildcards)
returns None and typer reads it, errors and all. ``tests/test_cli_validate_fast.py``
checks the options against the typer command and the values against typer's for many
command lines.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

from gadgetctl.cli.choices import CheckLevel, ColorMode, DiagnosticFormat
from gadgetctl.cli.validate_run import (
    DEFAULT_COLOR,
    DEFAULT_FORMAT,
    DEFAULT_LEVEL,
    DEFAULT_MAX_SIZE,
)

#: Options that take a value, and the parameter they set.
VALUE_OPTIONS: dict[str, str] = {
    "--format": "fmt",
    "-f": "fmt",
    "--definitions": "definitions",
    "-d": "definitions",
    "--level": "level",
    "--max-size": "max_size",
    "--color": "color",
}
#: Flags: the parameter they set, and to what.
FLAGS: dict[str, tuple[str, bool]] = {
    "--strict": ("strict", True),
    "--together": ("together", True),
    "--bundled": ("bundled", True),
    "--no-bundled": ("bundled", False),
    "--hints": ("hints", True),
    "--no-hints": ("hints", False),
}
_CHOICES = {"fmt": DiagnosticFormat, "level": CheckLevel, "color": ColorMode}
#: The variable that asks Click for shell completion (typer answers it).
COMPLETE_VAR = "_GADGETCTL_COMPLETE"


def parse(args: Sequence[str], environ: Mapping[str, str]) -> dict[str, object] | None:
    """The arguments of :func:`run_validate` for the words after ``validate``, or None
    when typer must read them."""
    if COMPLETE_VAR in environ or os.name == "nt":  # (Click expands wildcards on Windows)
        return None
    found: dict[str, object] = {
        "fmt": DEFAULT_FORMAT,
        "strict": False,
        "definitions": [],
        "bundled": True,
        "together": False,
        "level": DEFAULT_LEVEL,
        "max_size": DEFAULT_MAX_SIZE,
        "hints": True,
        "color": DEFAULT_COLOR,
    }
    paths: list[Path] = []
    words = iter(args)
    for word in words:
        if not word.startswith("-"):
            if not _plain_path(word):
                return None
            paths.append(Path(word))
            continue
        flag = FLAGS.get(word)
        if flag is not None:
            found[flag[0]] = flag[1]  # (the last one wins, as in Click)
            continue
        name, equals, value = word.partition("=")
        if equals and not name.startswith("--"):
            return None  # (-f=json: Click reads the value "=json")
        target = VALUE_OPTIONS.get(name)
        if target is None:
            return None
        if not equals:
            value = next(words, None)
            if value is None:
                return None
        read = _value(target, value)
        if read is None:
            return None
        if target == "definitions":
            found["definitions"].append(read)  # type: ignore[union-attr]
        else:
            found[target] = read
    if not paths:
        return None
    return {"paths": paths, **found}


def _value(target: str, value: str) -> object | None:
    if not value or value.startswith("-"):
        return None
    if target == "definitions":
        return Path(value) if _plain_path(value) else None
    if target == "max_size":
        if not (value.isascii() and value.isdigit()) or int(value) < 1:
            return None
        return int(value)
    choices = _CHOICES[target]
    return choices(value) if value in {member.value for member in choices} else None


def _plain_path(word: str) -> bool:
    """Whether typer takes ``word`` as a path without a word to say: not empty, and missing
    or readable (its path type says "... is not readable." of an unreadable one)."""
    if not word:
        return False
    try:
        os.stat(word)
    except OSError:
        return True
    except ValueError:  # a NUL in the word
        return False
    return os.access(word, os.R_OK)
