"""`gadgetctl view --replay FILE [CONFIG...]`: the input manager that replays a recording
under a :class:`~gadgetctl.view.timeline.ReplayTimeline`, set up as `gadgetctl replay` sets
up its own (replay devices in place of the recorded devices; the configuration's proxies,
filters, aliases, displays and users stay)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from gadgetctl.errors import GadgetctlError
from gadgetctl.view.timeline import ReplayTimeline


@dataclass(slots=True)
class ViewReplay:
    manager: object
    configuration: object
    timeline: ReplayTimeline
    notes: list[str] = field(default_factory=list)


def open_view_replay(
    recording: Path,
    configs: list[Path],
    *,
    definitions: list[Path],
    bundled: bool,
    driver_dirs: list[Path],
) -> ViewReplay:
    """Read ``recording`` (a gadgetctl recording or a VRPN log) and configure an input
    manager to replay it; raises :class:`GadgetctlError` with one line when it cannot."""
    from gadgetctl.files import require_file
    from gadgetctl.input.clock import now
    from gadgetctl.input.definitions import repository_for
    from gadgetctl.input.manager import InputManager, ManagerOptions
    from gadgetctl.jccl.configload import require_loadable
    from gadgetctl.monitor import replaydevice
    from gadgetctl.monitor.recording import RecordingError, read_recording
    from gadgetctl.monitor.vrpnlog import is_vrpn_log, read_vrpn_log

    require_file(recording)
    try:
        source = read_vrpn_log(recording) if is_vrpn_log(recording) else read_recording(recording)
        schedule = replaydevice.make_schedule(source.records, speed=1.0, loop=False, mapping={})
    except RecordingError as err:
        raise GadgetctlError(str(err)) from None
    except ValueError as err:
        raise GadgetctlError(f"{recording}: {err}") from None
    notes = [f"{recording}: {p}" for p in source.problems if p.severity != "info"]
    options = ManagerOptions(driver_dirs=list(driver_dirs))
    if configs:
        manager, configuration = InputManager.from_files(
            configs, definitions=list(definitions), bundled=bundled, options=options
        )
    else:
        repo = repository_for(
            None, definitions=list(definitions), bundled=bundled, driver_dirs=options.driver_dirs
        )
        manager, configuration = InputManager(repo, options), None
    try:
        if configuration is not None:
            require_loadable(configuration)
        recorded = replaydevice.recorded_devices(source.header, schedule, {})
        replaydevice.check_mapping({}, recorded, configuration, recording)
        replaydevice.install(manager)
        plan = replaydevice.plan_replay(source.header, schedule, recording, configuration, {})
        feeder = replaydevice.ReplayFeeder(
            schedule, manager.device, {name: d.units for name, d in plan.devices.items()}
        )
    except BaseException:
        manager.shutdown()
        raise
    return ViewReplay(
        manager, plan.configuration, ReplayTimeline(schedule, feeder, now), notes + plan.notes
    )
