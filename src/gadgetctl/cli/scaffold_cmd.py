"""`gadgetctl scaffold driver`: generate a driver plug-in that works on the first run."""

from __future__ import annotations

import json
from enum import StrEnum
from pathlib import Path

import typer

from gadgetctl.cli.options import DataFormat, emit
from gadgetctl.scaffold.model import DEFAULT_TRANSPORT, TRANSPORT_NAMES, TYPE_NAMES

DeviceTypeChoice = StrEnum("DeviceTypeChoice", {name: name for name in TYPE_NAMES})
TransportChoice = StrEnum("TransportChoice", {name: name for name in TRANSPORT_NAMES})

scaffold_app = typer.Typer(
    help="Generate new things: a driver plug-in that works on the first run.", no_args_is_help=True
)


def register(app: typer.Typer) -> None:
    app.add_typer(scaffold_app, name="scaffold")


@scaffold_app.command("driver")
def driver(
    name: str = typer.Argument(
        ...,
        metavar="NAME",
        show_default=False,
        help="The device's name, CamelCase or snake_case: AcmeWand (or acme_wand) gives the plug-in "
        "AcmeWand_drv and the element type acme_wand.",
    ),
    types: list[DeviceTypeChoice] = typer.Option(
        [],
        "--type",
        "-t",
        metavar="TYPE",
        show_default=False,
        help=f"A device type the driver provides: {', '.join(TYPE_NAMES)}. Repeatable; default: "
        "digital.",
    ),
    transport: TransportChoice = typer.Option(
        TransportChoice(DEFAULT_TRANSPORT),
        "--transport",
        help="How the driver reaches the device: serial (pyserial, port and baud), udp (a port it "
        "receives on), tcp (host and port it connects to), file (a device file; a FIFO works) "
        "or none (the driver makes its own data).",
    ),
    vendor: str = typer.Option(
        "", "--vendor", metavar="NAME", help="The maker's name, for labels and documentation."
    ),
    directory: Path = typer.Option(
        Path("."),
        "--dir",
        metavar="DIR",
        help="Where to create the plug-in folder (or the project, with --package).",
    ),
    package: bool = typer.Option(
        False,
        "--package",
        help="Make an installable project (pyproject.toml, src/ layout) whose entry point in the "
        "gadgetctl.drivers group names the plug-in, instead of a folder for a driver path.",
    ),
    dry_run: bool = typer.Option(
        False, "--dry-run", help="List the files that would be written; write nothing."
    ),
    force: bool = typer.Option(
        False,
        "--force",
        help="Write into an existing directory, overwriting the generated files (others are kept).",
    ),
    fmt: DataFormat = typer.Option(DataFormat.text, "--format", "-f", help="Output format."),
) -> None:
    """Generate a driver plug-in that validates, loads, runs against its emulator and passes
    its tests as it is: standalone driver (the protocol: open, sample, close), wrapper for the
    input manager, .jdef, example.jconf, an emulator of a placeholder protocol over the chosen
    transport, pytest tests and a README saying where the real protocol goes.

    Exit status: 0 written (or listed with --dry-run), 2 refused: an invalid NAME or one
    that clashes with a standard definition or a bundled plug-in, or an existing directory
    without --force.
    """
    from gadgetctl.scaffold import DriverSpec, scaffold, summary_lines

    spec = DriverSpec.create(
        name,
        [str(t) for t in types],
        str(transport),
        vendor=vendor,
        package=package,
        directory=directory,
    )
    result = scaffold(spec, force=force, dry_run=dry_run)
    if fmt is DataFormat.json:
        emit(json.dumps(result.to_dict(), indent=2))
    else:
        emit("\n".join(summary_lines(result, Path.cwd())))
