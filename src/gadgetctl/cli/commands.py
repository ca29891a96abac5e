"""Registration of every command module with the application."""

from __future__ import annotations

import importlib

import typer

# Each module defines ``register(app)``, which adds the command (or group) named here.
# Order is the order of `gadgetctl --help`.
COMMANDS = {
    "validate": "gadgetctl.cli.validate_cmd",
    "explain": "gadgetctl.cli.explain_cmd",
    "defs": "gadgetctl.cli.defs_cmd",
    "config": "gadgetctl.cli.config_cmd",
    "upgrade": "gadgetctl.cli.upgrade_cmd",
    "lsp": "gadgetctl.cli.lsp_cmd",
    "drivers": "gadgetctl.cli.drivers_cmd",
    "monitor": "gadgetctl.cli.monitor_cmd",
    "replay": "gadgetctl.cli.replay_cmd",
    "serve": "gadgetctl.cli.serve_cmd",
    "view": "gadgetctl.cli.view_cmd",
    "emulate": "gadgetctl.cli.emulate_cmd",
    "doctor": "gadgetctl.cli.doctor_cmd",
    "scaffold": "gadgetctl.cli.scaffold_cmd",
    "completion": "gadgetctl.cli.completion_cmd",
    "demo": "gadgetctl.cli.demo_cmd",
}
COMMAND_MODULES = tuple(COMMANDS.values())


def register_all(app: typer.Typer, only: str | None = None) -> None:
    """Register every command, or only the command named ``only`` (a key of
    :data:`COMMANDS`): a command line that names its command needs no other, and each
    costs imports and typer's reading of its signature."""
    names = COMMAND_MODULES if only is None else (COMMANDS[only],)
    for name in names:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as err:
            if err.name == name:  # a command not built yet
                continue
            raise
        module.register(app)
