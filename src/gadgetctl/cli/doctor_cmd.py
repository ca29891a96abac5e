"""`gadgetctl doctor [CONFIG...]`: why no data arrive."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from gadgetctl.cli.drivers_cmd import DRIVER_PATH_OPTION, TRUST_OPTION
from gadgetctl.cli.options import BUNDLED_OPTION, DEFINITIONS_OPTION, DataFormat, emit


def register(app: typer.Typer) -> None:
    app.command("doctor")(doctor)


def doctor(
    arguments: list[str] = typer.Argument(
        None,
        metavar="[CONFIG...]",
        show_default=False,
        help="Configuration files, loaded together as one configuration, and VRPN devices to check (vrpn:Device@host[:port], vrpn:Device@tcp://host:port).",
    ),
    probe: bool = typer.Option(
        False,
        "--probe",
        help="Connect to the TCP and VRPN servers the configuration and vrpn: names name (and nothing else).",
    ),
    timeout: float = typer.Option(
        2.0, "--timeout", metavar="SECONDS", help="Seconds to wait for each --probe connection."
    ),
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
    driver_paths: list[Path] = DRIVER_PATH_OPTION,
    trust_driver_path: bool = TRUST_OPTION,
    fmt: DataFormat = typer.Option(DataFormat.text, "--format", "-f", help="Output format."),
    serve_port: str | None = typer.Option(
        None,
        "--serve-port",
        metavar="[ADDR:]PORT",
        help="Check that `gadgetctl serve` could bind this TCP and UDP port (on ADDR, default 127.0.0.1); a taken port names the process holding it.",
    ),
) -> None:
    """Explain why no data arrive: which definitions and driver plug-ins are found and
    whether each loads; for each configured device, its driver and whether its port exists
    and is usable by you (device files and serial ports: present, readable; UDP ports: free;
    TCP servers: answering, with --probe only). Without CONFIG: an overview of this system
    (search paths, drivers, serial ports, joystick devices).

    For VRPN devices (vrpn elements, vrpn:Device@host arguments): the host resolves, and
    with --probe a VRPN server answers, its version, and whether it announces the device
    (if not, the names it does announce).

    Nothing is sent to a device, and without --probe the network is never touched (a
    VRPN host name is resolved).
    Exit status: 0 when nothing blocks data, 1 when a finding would stop data from
    arriving, 2 on usage or tool errors.
    """
    from gadgetctl.doctor import DoctorOptions, diagnose, render_text
    from gadgetctl.monitor.vrpnwatch import PREFIX, is_vrpn_argument
    from gadgetctl.serve.address import parse_serve_port

    given = list(arguments or [])
    configs = [Path(a) for a in given if not is_vrpn_argument(a)]
    vrpn_names = [a[len(PREFIX) :] for a in given if is_vrpn_argument(a)]
    options = DoctorOptions(
        definitions=list(definitions),
        bundled=bundled,
        driver_dirs=list(driver_paths),
        probe=probe,
        timeout=timeout,
        vrpn_names=vrpn_names,
        serve_port=None if serve_port is None else parse_serve_port(serve_port),
    )
    report = diagnose(configs, options)
    if fmt is DataFormat.json:
        emit(json.dumps(report.to_dict(), indent=2))
    else:
        emit(render_text(report))
    raise typer.Exit(report.exit_code)
