"""`gadgetctl monitor`: live sample monitors on the embedded input manager."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Mapping
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from gadgetctl.cli.drivers_cmd import DRIVER_PATH_OPTION, TRUST_OPTION
from gadgetctl.cli.exiting import finish
from gadgetctl.cli.monitor_format import OutputFormat, PoseFormat
from gadgetctl.cli.options import BUNDLED_OPTION, DEFINITIONS_OPTION


class LengthUnits(StrEnum):
    meters = "meters"
    feet = "feet"
    inches = "inches"
    centimeters = "centimeters"


RATE_OPTION = typer.Option(
    60.0, "--rate", metavar="HZ", help="Frames per second (the view refreshes once per frame)."
)
DURATION_OPTION = typer.Option(
    None,
    "--duration",
    metavar="SECONDS",
    help="Stop after this many seconds (default: until q, Ctrl-C or SIGTERM).",
)
FORMAT_OPTION = typer.Option(
    None,
    "--format",
    "-f",
    help="live: the dashboard (needs a terminal); table: a plain-text table every --interval seconds; ndjson: one JSON record per sample on stdout; events: one line per change (button pressed or released, an axis beyond --dead-band, a pose beyond --pose-threshold or --angle-threshold). Default: live on a terminal, table otherwise.",
    show_default=False,
)
PER_FRAME_OPTION = typer.Option(
    False,
    "--per-frame",
    help="With --format ndjson: one frame record per frame instead of one record per sample.",
)
RECORD_OPTION = typer.Option(
    None,
    "--record",
    metavar="FILE",
    help="Write every sample, status change and marker to FILE (the recording format); complete even after Ctrl-C or SIGTERM.",
)
OVERWRITE_OPTION = typer.Option(False, "--overwrite", help="Replace an existing --record file.")
STATS_OPTION = typer.Option(
    False,
    "--stats",
    help="Print end-of-run statistics per device (always written as a stats record in ndjson).",
)
UNITS_OPTION = typer.Option(
    LengthUnits.meters,
    "--units",
    help="Length unit of displayed positions (records stay in meters).",
)
QUATERNION_OPTION = typer.Option(
    False, "--quaternion", help="Also show orientations as quaternions (w x y z)."
)
POSE_OPTION = typer.Option(
    None,
    "--pose",
    help="How positions are written in ndjson, the table and events: matrix (4x4; the default of ndjson), quaternion (position + w x y z) or euler (position + X-Y-Z angles in degrees, gmtl's EulerAngleXYZ as VR Juggler's position filters use; the default of events). Without it the table shows the translation and Euler angles (--quaternion adds w x y z).",
    show_default=False,
)
DEAD_BAND_OPTION = typer.Option(
    0.02,
    "--dead-band",
    metavar="SHARE",
    help="--format events: report an analog unit when it moved more than this share of its device's range (min..max) since it was last reported.",
)

if TYPE_CHECKING:
    from gadgetctl.jccl.xmlload import XmlDocument
POSE_THRESHOLD_OPTION = typer.Option(
    0.01,
    "--pose-threshold",
    metavar="METERS",
    help="--format events: report a position when it moved more than this distance since it was last reported.",
)
ANGLE_THRESHOLD_OPTION = typer.Option(
    1.0,
    "--angle-threshold",
    metavar="DEGREES",
    help="--format events: report a position (or glove joint) when it turned more than this angle since it was last reported.",
)
INTERVAL_OPTION = typer.Option(
    1.0, "--interval", metavar="SECONDS", help="Seconds between two tables of --format table."
)
MOUSE_OPTION = typer.Option(
    True,
    "--mouse/--no-mouse",
    help="Live view: report mouse buttons, motion and wheel to the keyboard_mouse_device.",
)
CHECK_OPTION = typer.Option(
    True,
    "--check/--no-check",
    help="Check the configurations first and print their errors and warnings as validate does (--no-check skips it).",
)
STRICT_OPTION = typer.Option(
    False,
    "--strict",
    help="Do not start when the configuration checks find errors (exit status 1).",
)
KEYBOARD_OPTION = typer.Option(
    None,
    "--keyboard",
    metavar="NAME",
    help="Live view: the keyboard_mouse_device that gets the keys and the mouse first (Tab gives them to the next one). Default: the first.",
)


ACCEPT_LOSS_OPTION = typer.Option(
    False,
    "--accept-loss",
    help="Exit 0 even when a device lost data (datagrams the kernel dropped for a full receive buffer, samples over the per-frame cap); without it such loss ends the run with exit status 1 and a line saying what was lost.",
)


def register(app: typer.Typer) -> None:
    app.command(name="monitor")(monitor)


def monitor(
    arguments: list[str] = typer.Argument(
        ...,
        metavar="CONFIG... [NAME...]",
        help="Configuration files (existing files ending in .jconf) and VRPN devices to watch without one (vrpn:Device@host[:port], vrpn:Device@tcp://host:port), then names or glob patterns of the devices, proxies and aliases to show (default: all).",
        show_default=False,
    ),
    rate: float = RATE_OPTION,
    duration: float | None = DURATION_OPTION,
    fmt: OutputFormat | None = FORMAT_OPTION,
    per_frame: bool = PER_FRAME_OPTION,
    record: Path | None = RECORD_OPTION,
    overwrite: bool = OVERWRITE_OPTION,
    stats: bool = STATS_OPTION,
    units: LengthUnits = UNITS_OPTION,
    quaternion: bool = QUATERNION_OPTION,
    pose: PoseFormat | None = POSE_OPTION,
    dead_band: float = DEAD_BAND_OPTION,
    pose_threshold: float = POSE_THRESHOLD_OPTION,
    angle_threshold: float = ANGLE_THRESHOLD_OPTION,
    interval: float = INTERVAL_OPTION,
    mouse: bool = MOUSE_OPTION,
    keyboard: str | None = KEYBOARD_OPTION,
    check: bool = CHECK_OPTION,
    strict: bool = STRICT_OPTION,
    accept_loss: bool = ACCEPT_LOSS_OPTION,
    driver_paths: list[Path] = DRIVER_PATH_OPTION,
    trust_driver_path: bool = TRUST_OPTION,
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
) -> None:
    """Run the input manager on CONFIG files and show every device, proxy and alias live:
    status, sample rate, samples per frame, dropped samples, age of the newest sample,
    jitter, and the values.

    Arguments that are existing files ending in .jconf are configurations; vrpn:Device@host
    arguments watch a VRPN device with no configuration (asked first for its layout); the others
    select what to show by name or glob pattern ('Wave*'). Keys in the live view: q quits,
    p pauses the display (sampling goes on), r resets the statistics, m writes a named
    marker, PgUp/PgDn scroll, Tab gives the keys to the next keyboard_mouse_device; other
    keys and the mouse go to that one device, as VR Juggler's simulator window does.

    Exit status: 0; 1 when a selected element ended pending, faulted, undecodable or
    stupefied, a device faulted, received data and decoded none of it, or lost data (unless
    --accept-loss); 2 for usage errors (unreadable configuration, unknown name).
    """
    from gadgetctl.monitor.vrpnwatch import is_vrpn_argument

    watched = [a for a in arguments if is_vrpn_argument(a)]
    configs, selectors = split_arguments(
        [a for a in arguments if not is_vrpn_argument(a)], require_config=not watched
    )
    parsed = {}
    if check:
        from gadgetctl.cli import exiting
        from gadgetctl.cli.preflight import check_before_running
        from gadgetctl.perf import built_to_last

        # what it parsed is what the run is built from: it lives to the end
        with built_to_last() if exiting.own_process else contextlib.nullcontext():
            parsed = check_before_running(
                configs, definitions=definitions, bundled=bundled, strict=strict
            )
    title = " ".join([*(str(p) for p in configs), *watched])  # as typed, no scratch file
    with watched_devices(configs, watched) as configs:
        code = run_monitor(
            configs,
            selectors,
            rate=rate,
            duration=duration,
            fmt=fmt,
            per_frame=per_frame,
            record=record,
            overwrite=overwrite,
            stats=stats,
            units=units.value,
            quaternion=quaternion,
            interval=interval,
            mouse=mouse,
            keyboard=keyboard,
            driver_paths=driver_paths,
            definitions=definitions,
            bundled=bundled,
            pose=pose.value if pose else None,
            thresholds=event_thresholds(dead_band, pose_threshold, angle_threshold),
            accept_loss=accept_loss,
            title=title,
            parsed=parsed,
        )
    # devices stopped, recordings closed: the process may end without freeing what the
    # run built (10,000 devices: the collector's last walk over them took most of a second)
    finish(code)


@contextlib.contextmanager
def watched_devices(configs: list[Path], watched: list[str]) -> Iterator[list[Path]]:
    """``configs`` plus, for ``vrpn:Device@host`` arguments, a scratch configuration with a
    vrpn element per device, laid out as the server shows it (removed afterwards)."""
    import tempfile

    from gadgetctl.monitor.vrpnwatch import write_configuration

    with tempfile.TemporaryDirectory(prefix="gadgetctl-vrpn-") as scratch:
        if watched:
            note = lambda line: typer.echo(line, err=True)  # noqa: E731
            configs = [*configs, write_configuration(watched, Path(scratch), note=note)]
        yield configs


def split_arguments(
    arguments: list[str], *, require_config: bool = True, command: str = "monitor"
) -> tuple[list[Path], list[str]]:
    """Existing ``*.jconf`` files are configurations, the rest NAME patterns; ``command``
    (monitor, serve) is named in the errors."""
    import os

    from gadgetctl.errors import GadgetctlError
    from gadgetctl.files import is_dir, is_file, require_file

    configs: list[Path] = []
    selectors: list[str] = []
    for argument in arguments:
        path = Path(argument)
        if argument.endswith(".jconf"):
            if is_file(path):
                configs.append(path)
                continue
            if os.path.exists(path) or not any(c in argument for c in "*?["):
                require_file(path)
        elif (argument.endswith("/") or not configs) and is_dir(path):
            raise GadgetctlError(
                f"{argument}: is a directory; {command} takes configuration files (*.jconf) "
                f"before the names to {'serve' if command == 'serve' else 'show'}"
            )
        selectors.append(argument)
    if not configs and require_config:
        first = Path(arguments[0])
        if is_file(first):
            raise GadgetctlError(
                f"{first}: not a configuration file (configurations end in .jconf)"
            )
        if os.path.exists(first) or "/" in arguments[0] or first.suffix:
            require_file(first)  # says what is wrong with a mistyped path
        raise GadgetctlError(
            "no configuration given: CONFIG arguments are existing files ending in .jconf"
            + (" (or vrpn:Device@host)" if command == "monitor" else "")
        )
    return configs, selectors


def fatal_load_errors(configuration) -> None:
    """A configuration that could not be read (missing, not XML, broken include) is a
    usage error: one line, exit status 2 (the rule of every command that runs one)."""
    from gadgetctl.jccl.configload import require_loadable

    require_loadable(configuration)


def check_options(rate: float, duration: float | None, interval: float) -> None:
    from gadgetctl.errors import GadgetctlError

    if not rate > 0 or rate > 10_000:
        raise GadgetctlError(
            f"--rate must be more than 0 and at most 10000 frames per second, not {rate:g}"
        )
    if duration is not None and not duration >= 0:
        raise GadgetctlError(f"--duration is a number of seconds, 0 or more, not {duration:g}")
    if not interval > 0:
        raise GadgetctlError(f"--interval must be positive, not {interval:g}")


def event_thresholds(dead_band: float, distance: float, angle: float):
    """The ``--dead-band``, ``--pose-threshold`` and ``--angle-threshold`` of ``--format events``."""
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.monitor.events import Thresholds

    for option, value in (
        ("--dead-band", dead_band),
        ("--pose-threshold", distance),
        ("--angle-threshold", angle),
    ):
        if not (value >= 0 and value < float("inf")):
            raise GadgetctlError(f"{option} must be a finite number >= 0, not {value:g}")
    return Thresholds(dead_band, distance, angle)


def check_keyboard(name: str | None, keyboards: list[str]) -> None:
    """``--keyboard NAME`` must name a keyboard_mouse_device of the configuration."""
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.suggest import did_you_mean

    if name is None or name in keyboards:
        return
    if not keyboards:
        raise GadgetctlError(f"--keyboard {name!r}: the configuration has no keyboard_mouse_device")
    hint = did_you_mean(name, keyboards)
    raise GadgetctlError(
        f"--keyboard {name!r}: no keyboard_mouse_device of that name"
        + (f"; {hint}" if hint else f" (there are: {', '.join(keyboards)})")
    )


def run_monitor(
    configs: list[Path],
    selectors: list[str],
    *,
    rate: float = 60.0,
    duration: float | None = None,
    fmt: OutputFormat | None = None,
    per_frame: bool = False,
    record: Path | None = None,
    overwrite: bool = False,
    stats: bool = False,
    units: str = "meters",
    quaternion: bool = False,
    interval: float = 1.0,
    mouse: bool = True,
    keyboard: str | None = None,
    driver_paths: list[Path] | None = None,
    definitions: list[Path] | None = None,
    bundled: bool = True,
    heading: str = "gadgetctl monitor",
    pose: str | None = None,
    thresholds=None,
    accept_loss: bool = False,
    title: str | None = None,
    parsed: Mapping[Path, XmlDocument] | None = None,
) -> int:
    from gadgetctl.cli import exiting
    from gadgetctl.cli.monitor_run import RunOptions, check_record_path, choose_format, run
    from gadgetctl.input.manager import InputManager, ManagerOptions
    from gadgetctl.monitor.session import MonitorSession
    from gadgetctl.perf import built_to_last

    check_options(rate, duration, interval)
    mode = choose_format(fmt, record)
    check_record_path(record, overwrite, mode)
    options = ManagerOptions(driver_dirs=list(driver_paths or ()))
    manager, configuration = InputManager.from_files(
        configs,
        definitions=list(definitions or ()),
        bundled=bundled,
        options=options,
        parsed=parsed,
    )
    fatal_load_errors(configuration)
    info = {"config": [str(p) for p in configs]}
    session = MonitorSession(manager, configuration, selectors=selectors, rate=rate, info=info)
    try:
        with built_to_last() if exiting.own_process else contextlib.nullcontext():
            session.start()  # what the session is built of lives to the end
    except BaseException:
        manager.shutdown()
        raise
    try:
        check_keyboard(keyboard, session.keyboards())
    except BaseException:
        manager.shutdown()
        raise
    notes = [
        f"{d.location}: {d.message}"
        for d in configuration.diagnostics
        if d.severity.value == "warning"
    ]
    if title is None:
        title = " ".join(str(p) for p in configs)
    return run(
        session,
        RunOptions(
            format=mode,
            duration=duration,
            per_frame=per_frame,
            stats=stats,
            record=record,
            overwrite=overwrite,
            interval=interval,
            length_unit=units,
            quaternion=quaternion,
            mouse=mouse,
            keyboard=keyboard,
            title=title,
            heading=heading,
            notes=notes,
            pose=pose,
            thresholds=thresholds,
            accept_loss=accept_loss,
        ),
    )
