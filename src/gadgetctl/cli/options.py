"""Options and small helpers shared by several commands."""

from __future__ import annotations

import os
import sys
from enum import StrEnum

import typer


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


COLOR_OPTION = typer.Option(
    ColorMode.auto, "--color", help="Colour the output: auto (only on a terminal), always or never."
)


def emit(text: str) -> None:
    if text:
        sys.stdout.write(text if text.endswith("\n") else text + "\n")


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
