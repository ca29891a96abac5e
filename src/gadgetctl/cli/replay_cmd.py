"""`gadgetctl replay`: play a recording back through the input manager, or summarise it."""

from __future__ import annotations

from pathlib import Path

import typer

from gadgetctl.cli.drivers_cmd import DRIVER_PATH_OPTION, TRUST_OPTION
from gadgetctl.cli.exiting import finish
from gadgetctl.cli.monitor_cmd import (
    ANGLE_THRESHOLD_OPTION,
    CHECK_OPTION,
    DEAD_BAND_OPTION,
    DURATION_OPTION,
    FORMAT_OPTION,
    INTERVAL_OPTION,
    MOUSE_OPTION,
    OVERWRITE_OPTION,
    PER_FRAME_OPTION,
    POSE_OPTION,
    POSE_THRESHOLD_OPTION,
    QUATERNION_OPTION,
    RATE_OPTION,
    STATS_OPTION,
    STRICT_OPTION,
    UNITS_OPTION,
    LengthUnits,
    OutputFormat,
    PoseFormat,
    event_thresholds,
)
from gadgetctl.cli.options import BUNDLED_OPTION, DEFINITIONS_OPTION, emit


def register(app: typer.Typer) -> None:
    app.command(name="replay")(replay)


def replay(
    recording: Path = typer.Argument(
        ...,
        metavar="FILE",
        help="A recording made with `gadgetctl monitor --record`, or a VRPN log file (.vrpn).",
        show_default=False,
    ),
    names: list[str] = typer.Argument(
        None,
        metavar="[NAME...]",
        help="Names or glob patterns of the devices, proxies and aliases to show (default: all).",
        show_default=False,
    ),
    speed: float = typer.Option(
        1.0, "--speed", metavar="X", help="Replay X times as fast as recorded (0.5: half speed)."
    ),
    loop: bool = typer.Option(
        False, "--loop", help="Start again at the end, until stopped (timestamps keep increasing)."
    ),
    configs: list[Path] = typer.Option(
        [],
        "--config",
        "-c",
        metavar="FILE",
        help="Replay against this configuration: its elements named like recorded devices become replay devices; proxies, filters and aliases stay. Repeatable. Default: a configuration synthesised from the recording's header.",
    ),
    mapping: list[str] = typer.Option(
        [],
        "--map",
        metavar="OLD=NEW",
        help="Feed the recorded device OLD to the device NEW of the configuration. Repeatable.",
    ),
    summary: bool = typer.Option(
        False,
        "--summary",
        help="Print per-device counts, rates, gaps and value ranges with sparklines instead of replaying (--format ndjson: as one JSON object).",
    ),
    rate: float = RATE_OPTION,
    duration: float | None = DURATION_OPTION,
    fmt: OutputFormat | None = FORMAT_OPTION,
    per_frame: bool = PER_FRAME_OPTION,
    record: Path | None = typer.Option(
        None, "--record", metavar="FILE", help="Record the replayed session to FILE."
    ),
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
    check: bool = CHECK_OPTION,
    strict: bool = STRICT_OPTION,
    driver_paths: list[Path] = DRIVER_PATH_OPTION,
    trust_driver_path: bool = TRUST_OPTION,
    definitions: list[Path] = DEFINITIONS_OPTION,
    bundled: bool = BUNDLED_OPTION,
) -> None:
    """Feed a recording back through a replay driver into the input manager, so proxies,
    filters, aliases and the monitor behave as with the live devices; the views and
    options are those of `gadgetctl monitor`. The replay ends with the recording (unless
    --loop).

    Exit status: 0; 1 when an element ended pending or stupefied; 2 when FILE is not a
    readable recording or an option is wrong.
    """
    if summary:
        _summary(recording, fmt)
        return
    if check and configs:
        from gadgetctl.cli.preflight import check_before_running

        check_before_running(list(configs), definitions=definitions, bundled=bundled, strict=strict)
    code = run_replay(
        recording,
        list(names or ()),
        speed=speed,
        loop=loop,
        configs=configs,
        mapping=mapping,
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
        driver_paths=driver_paths,
        definitions=definitions,
        bundled=bundled,
        pose=pose.value if pose else None,
        thresholds=event_thresholds(dead_band, pose_threshold, angle_threshold),
    )
    # devices stopped, recordings closed: the process may end without freeing what the
    # run built (10,000 devices: the collector's last walk over them took most of a second)
    finish(code)


def parse_mapping(items: list[str]) -> dict[str, str]:
    from gadgetctl.errors import GadgetctlError

    result: dict[str, str] = {}
    for item in items:
        old, sep, new = item.partition("=")
        if not sep or not old or not new:
            raise GadgetctlError(
                f"--map {item!r}: expected OLD=NEW (recorded name=name in the configuration)"
            )
        if old in result:
            raise GadgetctlError(f"--map: {old!r} is mapped twice")
        result[old] = new
    return result


def open_recording(path: Path):
    """A gadgetctl recording, or a VRPN log file (it starts with a VRPN cookie) read as one."""
    from gadgetctl.monitor.recording import read_recording
    from gadgetctl.monitor.vrpnlog import is_vrpn_log, read_vrpn_log

    return read_vrpn_log(path) if is_vrpn_log(path) else read_recording(path)


def _open_vrpn_log(path: Path, configs: list[Path], renames: dict[str, str]):
    """A VRPN log whose senders are routed to devices: by ``--map SENDER=DEVICE`` (several
    senders may name one device), else, with --config, to the ``vrpn`` elements whose
    tracker/button/analog servers name them; the renames left for the replay are identities
    of the mapped devices, so that each is checked against the configuration."""
    from gadgetctl.jccl.configload import load_configuration
    from gadgetctl.monitor.vrpnlog import read_vrpn_log, routes_from_configuration

    routes: dict = {}
    if configs:
        routes.update(routes_from_configuration(load_configuration(configs)))
    routes.update(renames)
    source = read_vrpn_log(path, routes)
    return source, {new: new for new in set(renames.values())}


def _summary(recording: Path, fmt: OutputFormat | None) -> None:
    import json

    from gadgetctl.cli.monitor_text import summary_text
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.monitor.recording import RecordingError
    from gadgetctl.monitor.summary import summarize

    try:
        result = summarize(open_recording(recording))
    except RecordingError as err:
        raise GadgetctlError(str(err)) from None
    if fmt is OutputFormat.ndjson:
        emit(json.dumps(result.to_dict()))
    else:
        emit(summary_text(result))


def run_replay(
    recording: Path,
    names: list[str],
    *,
    speed: float = 1.0,
    loop: bool = False,
    configs: list[Path] | None = None,
    mapping: list[str] | None = None,
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
    driver_paths: list[Path] | None = None,
    definitions: list[Path] | None = None,
    bundled: bool = True,
    pose: str | None = None,
    thresholds=None,
) -> int:
    import math

    from gadgetctl.cli.monitor_cmd import check_options, fatal_load_errors
    from gadgetctl.cli.monitor_run import RunOptions, check_record_path, choose_format, run
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.input.manager import InputManager, ManagerOptions
    from gadgetctl.monitor import replaydevice
    from gadgetctl.monitor.recording import RecordingError
    from gadgetctl.monitor.records import REPLAY_UNITS
    from gadgetctl.monitor.replay import MAX_PAUSE
    from gadgetctl.monitor.session import MonitorSession

    check_options(rate, duration, interval)
    if not (speed > 0 and math.isfinite(speed)):
        raise GadgetctlError(f"--speed must be a positive number, not {speed:g}")
    renames = parse_mapping(list(mapping or ()))
    mode = choose_format(fmt, record)
    check_record_path(record, overwrite, mode)
    if (
        record is not None
        and str(record) != "-"
        and record.exists()
        and record.resolve() == recording.resolve()
    ):
        raise GadgetctlError(f"{record}: cannot record over the recording being replayed")
    configs = list(configs or ())
    from gadgetctl.files import require_file

    for path in configs:
        require_file(path)
    from gadgetctl.monitor.vrpnlog import is_vrpn_log

    vrpn_log = is_vrpn_log(recording)
    try:
        if vrpn_log:  # the log's devices are routed (and merged) while it is read
            source, renames = _open_vrpn_log(recording, configs, renames)
        else:
            source = open_recording(recording)
        schedule = replaydevice.make_schedule(
            source.records, speed=speed, loop=loop, mapping=renames
        )
    except RecordingError as err:
        raise GadgetctlError(str(err)) from None
    except ValueError as err:
        raise GadgetctlError(f"{recording}: {err}") from None
    notes = [f"{recording}: {problem}" for problem in source.problems if problem.severity != "info"]
    if schedule.pauses_shortened:
        count = schedule.pauses_shortened
        notes.append(
            f"{recording}: {count} pause{'' if count == 1 else 's'} longer than "
            f"{MAX_PAUSE:g} s of replay shortened to {MAX_PAUSE:g} s "
            f"(the longest: {schedule.longest_pause:.6g} s recorded)"
        )
    if schedule.units_beyond:
        notes.append(
            f"{recording}: {schedule.units_beyond} "
            f"sample{'' if schedule.units_beyond == 1 else 's'} of units beyond "
            f"{REPLAY_UNITS - 1} skipped (a replay plays units 0 to {REPLAY_UNITS - 1} "
            "of a device and kind)"
        )
    notes += [
        f"--map: {warning}"
        for warning in schedule.mapping_warnings
        if "does not occur" not in warning
    ]
    recorded = replaydevice.recorded_devices(source.header, schedule, {})
    options = ManagerOptions(driver_dirs=list(driver_paths or ()))
    if configs:
        manager, configuration = InputManager.from_files(
            configs, definitions=list(definitions or ()), bundled=bundled, options=options
        )
        try:
            fatal_load_errors(configuration)
            replaydevice.check_mapping(renames, recorded, configuration, recording)
        except BaseException:
            manager.shutdown()
            raise
    else:
        replaydevice.check_mapping(renames, recorded, None, recording)
        from gadgetctl.input.definitions import repository_for

        manager = InputManager(
            repository_for(
                None,
                definitions=list(definitions or ()),
                bundled=bundled,
                driver_dirs=options.driver_dirs,
            ),
            options,
        )
        configuration = None
    try:
        replaydevice.install(manager)
        plan = replaydevice.plan_replay(source.header, schedule, recording, configuration, renames)
        notes += plan.notes
        feeder = replaydevice.ReplayFeeder(
            schedule, manager.device, {name: device.units for name, device in plan.devices.items()}
        )
        info = {"replay_of": str(recording), "speed": speed, "config": [str(p) for p in configs]}
        session = MonitorSession(
            manager, plan.configuration, selectors=names, rate=rate, source=feeder, info=info
        )
        session.start()
    except BaseException:
        manager.shutdown()
        raise
    title = f"{recording} at x{speed:g}" + (" (loop)" if loop else "")
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
            title=title,
            heading="gadgetctl replay",
            notes=notes,
            pose=pose,
            thresholds=thresholds,
        ),
        feeder=feeder,
    )
