"""Registration of every command module with the application."""

from __future__ import annotations

import importlib

import typer

# Each module defines ``register(app)``. Order is the order of `gadgetctl --help`.
COMMAND_MODULES = (
    "gadgetctl.cli.validate_cmd",
    "gadgetctl.cli.explain_cmd",
    "gadgetctl.cli.defs_cmd",
    "gadgetctl.cli.config_cmd",
    "gadgetctl.cli.upgrade_cmd",
    "gadgetctl.cli.lsp_cmd",
    "gadgetctl.cli.drivers_cmd",
    "gadgetctl.cli.monitor_cmd",
    "gadgetctl.cli.replay_cmd",
    "gadgetctl.cli.serve_cmd",
    "gadgetctl.cli.view_cmd",
    "gadgetctl.cli.emulate_cmd",
    "gadgetctl.cli.doctor_cmd",
    "gadgetctl.cli.scaffold_cmd",
    "gadgetctl.cli.completion_cmd",
    "gadgetctl.cli.demo_cmd",
)


def register_all(app: typer.Typer) -> None:
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as err:
            if err.name == name:  # a command not built yet
                continue
            raise
        module.register(app)
