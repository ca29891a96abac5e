"""The choices of shared options and the helpers that act on them, without the CLI
framework: a command line parsed without typer (:mod:`gadgetctl.cli.validate_fast`) uses
the same ones. :mod:`gadgetctl.cli.options` re-exports them with the typer options."""

from __future__ import annotations

import os
import sys
from enum import StrEnum


class DiagnosticFormat(StrEnum):
    text = "text"
    json = "json"
    github = "github"
    sarif = "sarif"


class CheckLevel(StrEnum):
    xml = "xml"
    schema = "schema"
    definitions = "definitions"
    full = "full"


class DataFormat(StrEnum):
    text = "text"
    json = "json"


class ColorMode(StrEnum):
    auto = "auto"
    always = "always"
    never = "never"


def use_color(mode: ColorMode, stream=None) -> bool:
    stream = stream or sys.stdout
    if mode is ColorMode.always:
        return True
    if mode is ColorMode.never or os.environ.get("NO_COLOR"):
        return False
    return hasattr(stream, "isatty") and stream.isatty()


def emit(text: str) -> None:
    if text:
        sys.stdout.write(text if text.endswith("\n") else text + "\n")
