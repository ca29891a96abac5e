"""`gadgetctl config pending`: what the input manager would leave pending, and why.

The command function is registered by `gadgetctl.cli.config_cmd` under the `config` group.
"""

from __future__ import annotations

import json
from pathlib import Path

import typer

from gadgetctl.cli.drivers_cmd import DRIVER_PATH_OPTION, TRUST_OPTION
from gadgetctl.cli.options import BUNDLED_OPTION, DEFINITIONS_OPTION, DataFormat, emit


def pending(
    files: list[Path] = typer.Argument(
        ...,
        metavar="FILES...",
        help="Configuration files, loaded together as one configuration.",
        show_default=False,
    ),
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
    fmt: DataFormat = typer.Option(DataFormat.text, "--format", "-f", help="Output format."),
    driver_paths: list[Path] = DRIVER_PATH_OPTION,
    trust_driver_path: bool = TRUST_OPTION,
    start: bool = typer.Option(
        False,
        "--start/--no-start",
        help="Also start the devices (opening their ports and connections) to find those that fail to start; everything is stopped again before the report.",
    ),
) -> None:
    """Configure the input manager from FILES and report the elements that stay pending,
    each with its reason, and the proxies that end up stupefied.

    Drivers named by input_manager elements are loaded (their code runs); devices are
    configured but, without --start, not started. Elements that are not about input
    (displays, users) are not reported. Exit status: 0 when nothing is pending or
    stupefied, 1 otherwise.
    """
    from gadgetctl.files import require_file
    from gadgetctl.input.manager import InputManager, ManagerOptions
    from gadgetctl.input.report import pending_report
    from gadgetctl.jccl.configload import require_loadable

    for path in files:
        require_file(path)
    options = ManagerOptions(
        start_devices=start, driver_dirs=list(driver_paths), retry_interval=None
    )
    manager, configuration = InputManager.from_files(
        files, definitions=definitions, bundled=bundled, options=options
    )
    require_loadable(configuration)
    with manager:
        manager.configure(configuration)
        if start:
            manager.update()
        report = pending_report(manager)
    if fmt is DataFormat.json:
        emit(json.dumps(report.to_dict(), indent=2))
    else:
        emit(report.text())
    raise typer.Exit(1 if report.problems else 0)
