"""Registration of every command module with the application."""

from __future__ import annotations

import importlib

import typer

# Each module defines ``register(app)``. Order is the order of `gadgetctl --help`.
COMMAND_MODULES = (
    "gadgetctl.cli.validate_cmd",
    "gadgetctl.cli.explain_cmd",
    "gadgetctl.cli.demo_cmd",
)


def register_all(app: typer.Typer) -> None:
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(app)
