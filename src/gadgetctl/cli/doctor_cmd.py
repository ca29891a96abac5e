"""`gadgetctl doctor [CONFIG...]`: why no data arrive."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from gadgetctl.cli.drivers_cmd import DRIVER_PATH_OPTION
from gadgetctl.cli.options import BUNDLED_OPTION, DEFINITIONS_OPTION, DataFormat, emit


def register(app: typer.Typer) -> None:
    app.command("doctor")(doctor)


def doctor(
    configs: list[Path] = typer.Argument(None, metavar="[CONFIG...]", show_default=False,
                                         help="Configuration files, loaded together as one configuration."),
    probe: bool = typer.Option(False, "--probe",
                               help="Connect to the TCP servers the configuration names (and nothing else)."),
    timeout: float = typer.Option(2.0, "--timeout", metavar="SECONDS", help="Seconds to wait for each --probe connection."),
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
    driver_paths: list[Path] = DRIVER_PATH_OPTION,
    fmt: DataFormat = typer.Option(DataFormat.text, "--format", "-f", help="Output format."),
    serve_port: str | None = typer.Option(None, "--serve-port", metavar="[ADDR:]PORT",
                                          help="Check that `gadgetctl serve` could bind this TCP and UDP port (on ADDR, default 127.0.0.1); a taken port names the process holding it."),
) -> None:
    """Explain why no data arrive: which definitions and driver plug-ins are found and
    whether each loads; for each configured device, its driver and whether its port exists
    and is usable by you (device files and serial ports: present, readable; UDP ports: free;
    TCP servers: answering, with --probe only). Without CONFIG: an overview of this system
    (search paths, drivers, serial ports, joystick devices).

    Nothing is sent to a device, and without --probe the network is never touched.
    Exit status: 0 when nothing blocks data, 1 when a finding would stop data from
    arriving, 2 on usage or tool errors.
    """
    from gadgetctl.doctor import DoctorOptions, diagnose, render_text
    from gadgetctl.serve.address import parse_serve_port

    options = DoctorOptions(definitions=list(definitions), bundled=bundled, driver_dirs=list(driver_paths),
                            probe=probe, timeout=timeout,
                            serve_port=None if serve_port is None else parse_serve_port(serve_port))
    report = diagnose(list(configs or []), options)
    if fmt is DataFormat.json:
        emit(json.dumps(report.to_dict(), indent=2))
    else:
        emit(render_text(report))
    raise typer.Exit(report.exit_code)
