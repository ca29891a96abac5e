"""`gadgetctl emulate DRIVER [OPTIONS...]`: run a driver plug-in's device emulator."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from gadgetctl.cli.options import DataFormat, emit

if TYPE_CHECKING:
    from gadgetctl.input.plugins.emulators import Emulator

PASS_THROUGH = {
    "allow_extra_args": True,
    "ignore_unknown_options": True,
    "allow_interspersed_args": False,
}


def register(app: typer.Typer) -> None:
    app.command("emulate", context_settings=PASS_THROUGH)(emulate)


def emulate(
    ctx: typer.Context,
    driver: str | None = typer.Argument(
        None,
        metavar="DRIVER",
        show_default=False,
        help="Plug-in name (DTrack_drv) or element type (dtrack), case-insensitive.",
    ),
    list_: bool = typer.Option(
        False, "--list", help="List the driver plug-ins that ship an emulator."
    ),
    driver_paths: list[Path] = typer.Option(
        [],
        "--driver-path",
        metavar="DIR",
        help="Also look for driver plug-ins in DIR (after the bundled drivers and GADGETCTL_DRIVER_PATH). Repeatable.",
    ),
    fmt: DataFormat = typer.Option(
        DataFormat.text, "--format", "-f", help="Output format of --list."
    ),
) -> None:
    """Run the device emulator a driver plug-in ships, and print where to point a
    configuration at it (a FIFO path, a UDP or TCP port, a pty path).

    Everything after DRIVER goes to the emulator: `gadgetctl emulate DTrack_drv --help`
    shows its options. Ctrl-C stops it (exit status 0). Exit status 2 when DRIVER names no
    plug-in or one without an emulator.
    """
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.input.definitions import driver_search_for
    from gadgetctl.input.plugins.emulators import EmulatorLookupError, emulators, find_emulator

    search = driver_search_for(None, driver_paths)
    if list_:
        if driver is not None:
            raise GadgetctlError("--list takes no DRIVER")
        _list(emulators(search), fmt)
        return
    if driver is None:
        raise GadgetctlError("name a DRIVER (gadgetctl emulate --list shows them)")
    try:
        emulator = find_emulator(driver, search)
    except EmulatorLookupError as err:
        raise GadgetctlError(str(err)) from None
    raise typer.Exit(_run(emulator, list(ctx.args)))


def _run(emulator: Emulator, argv: list[str]) -> int:
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.input.errors import describe
    from gadgetctl.input.plugins.emulators import load_emulator
    from gadgetctl.input.plugins.metadata import missing_requirements

    missing = missing_requirements(emulator.plugin.metadata)
    if missing:
        raise GadgetctlError(f"emulate {emulator.plugin.name}: {'; '.join(missing)}")

    try:
        module = load_emulator(emulator)
    except KeyboardInterrupt:
        return 0
    except (Exception, SystemExit) as err:
        raise GadgetctlError(f"cannot load {emulator.path}: {describe(err)}") from None
    main = getattr(module, "main", None)
    if not callable(main):
        raise GadgetctlError(f"{emulator.path} has no main(argv) function")
    try:
        code = main(argv)
    except KeyboardInterrupt:
        return 0
    except SystemExit as exit_:  # argparse: --help, usage errors
        code = exit_.code
    except OSError as err:  # its port, link or FIFO: named in one line, a tool error
        raise GadgetctlError(f"emulate {emulator.plugin.name}: {describe(err)}") from None
    except Exception as err:
        typer.echo(
            f"gadgetctl: error: the {emulator.plugin.name} emulator failed: {describe(err)}",
            err=True,
        )
        return 1
    if code is None or isinstance(code, bool):
        return int(bool(code))
    return code if isinstance(code, int) else 1


def _list(found: list[Emulator], fmt: DataFormat) -> None:
    if fmt is DataFormat.json:
        emit(json.dumps({"emulators": [e.to_dict() for e in found]}, indent=2))
        return
    if not found:
        emit("no driver plug-in ships an emulator")
        return
    lines = []
    for emulator in found:
        types = (
            ", ".join(sorted(emulator.plugin.declared_types()[0])) or "no declared element types"
        )
        lines.append(f"{emulator.plugin.name}  ({types})  {emulator.path}")
        if emulator.summary:
            lines.append(f"    {emulator.summary}")
    emit("\n".join(lines))
