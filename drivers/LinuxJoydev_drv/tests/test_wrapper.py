"""The joydev device in the input manager, against the FIFO emulator: configurations, units
through proxies and aliases, garbage, disconnection and reconnection, the corpus example."""

from __future__ import annotations

from pathlib import Path

import pytest
from LinuxJoydev_drv.emulator import AXIS_HIGH, AXIS_LOW, JoydevEmulator

from gadgetctl.input import DeviceKind, DigitalState
from gadgetctl.input.testing import frames_until
from gadgetctl.input.testing.commands import monitor_ndjson, samples_of
from gadgetctl.input.testing.configs import alias, configuration, corpus_copy, pending_in, proxy
from gadgetctl.input.testing.fixtures import managers_fixture

pytestmark = pytest.mark.timeout(30)

PRESSED = (DigitalState.ON, DigitalState.TOGGLE_ON)


def joystick(name: str, fifo: Path, *extra: str) -> str:
    return f'<linux_joydev name="{name}" version="1"><port_name>{fifo}</port_name>{"".join(extra)}</linux_joydev>\n'


build = managers_fixture("LinuxJoydev_drv", name="build", ready=True)


# -- units through proxies and aliases --------------------------------------------------------


def test_every_button_toggles_on_and_off_through_its_alias(tmp_path: Path, build) -> None:
    body = joystick("Stick", tmp_path / "js0")
    for b in range(12):
        body += proxy("digital", f"Button {b}", "Stick", b) + alias(f"VJButton{b}", f"Button {b}")
    with JoydevEmulator(directory=tmp_path, scenario="buttons", rate=500.0):
        manager = build(body)
        seen: dict[int, set[DigitalState]] = {b: set() for b in range(12)}

        def all_toggled() -> bool:
            for b in range(12):
                seen[b].add(manager.proxy(f"VJButton{b}").data)
            return all(
                {DigitalState.TOGGLE_ON, DigitalState.TOGGLE_OFF} <= s for s in seen.values()
            )

        frames_until(manager, all_toggled)
    # one sample per event: a press and its release never merge into one state
    assert manager.device("Stick").store.total(DeviceKind.DIGITAL) > 24


def test_axes_are_normalised_and_axis_buttons_follow_the_middle(tmp_path: Path, build) -> None:
    body = joystick(
        "Stick", tmp_path / "js0", "<axis_buttons>2</axis_buttons><axis_buttons>0</axis_buttons>"
    )
    body += proxy("analog", "Axis 2", "Stick", 2) + alias("VJAxis2", "Axis 2")
    body += proxy("digital", "Axis 2 Low", "Stick", 12) + proxy(
        "digital", "Axis 2 High", "Stick", 13
    )
    body += proxy("digital", "Axis 0 Low", "Stick", 14)
    with JoydevEmulator(directory=tmp_path, scenario="buttons", rate=400.0):
        manager = build(body)
        seen: set[tuple[float, bool, bool]] = set()

        def swept() -> bool:
            value = manager.proxy("VJAxis2").data
            low = manager.proxy("Axis 2 Low").data in PRESSED
            high = manager.proxy("Axis 2 High").data in PRESSED
            seen.add((value, low, high))
            return {(0.0, True, False), (0.5, False, False), (1.0, False, True)} <= seen

        frames_until(manager, swept)
    device = manager.device("Stick")
    assert device.analog_min == -32767 and device.analog_max == 32767  # the definition's defaults
    assert manager.proxy("Axis 2").raw in (AXIS_LOW, 0, AXIS_HIGH)
    assert manager.proxy("Axis 0 Low").reason is None  # units 12-15: two pairs after 12 buttons


def test_the_elements_min_and_max_set_the_analog_range(tmp_path: Path, build) -> None:
    range_ = "<axis_buttons>1</axis_buttons><min>0.0</min><max>32767.0</max>"
    body = joystick("Stick", tmp_path / "js0", range_)
    body += proxy("analog", "Axis 1", "Stick", 1) + proxy("digital", "Axis 1 High", "Stick", 3)
    with JoydevEmulator(directory=tmp_path, scenario="buttons", rate=400.0, buttons=2, axes=2):
        manager = build(body)
        seen: set[tuple[float, bool]] = set()

        def swept() -> bool:
            seen.add((manager.proxy("Axis 1").data, manager.proxy("Axis 1 High").data in PRESSED))
            return {(0.0, False), (1.0, True)} <= seen

        frames_until(manager, swept)
    # the middle of 0..32767 decides the virtual buttons: raw 0 is "low", never 0.5
    assert all(value in (0.0, 1.0) for value, _ in seen)


def test_garbage_is_skipped_counted_and_never_becomes_a_value(tmp_path: Path, build) -> None:
    body = joystick("Stick", tmp_path / "js0")
    body += "".join(proxy("analog", f"Axis {a}", "Stick", a) for a in range(6))
    with JoydevEmulator(directory=tmp_path, scenario="garbage", rate=1000.0, seed=5) as emu:
        manager = build(body)
        device = manager.device("Stick")
        values: dict[int, set[float]] = {a: set() for a in range(6)}

        def collected() -> bool:
            frame = device.store.frame(DeviceKind.ANALOG)
            for a in range(6):
                values[a].update(frame.column(a))
            return device.counters.get("resyncs", 0) >= 20 and device.store.total() > 200

        frames_until(manager, collected)
        sent = emu.sent_events()
        assert manager.status("Stick").state == "running" and device.faults == 0
    for a in range(6):
        assert values[a] <= {0.0} | {float(v) for _t, v, kind, n in sent if kind & 0x02 and n == a}
    assert device.counters["skipped_bytes"] > 0


# -- disconnection ------------------------------------------------------------------------------


def test_a_lost_device_faults_and_resumes_within_two_seconds(tmp_path: Path, build) -> None:
    fifo, other_fifo = tmp_path / "js0", tmp_path / "js1"
    body = joystick("Stick", fifo) + joystick("Other", other_fifo)
    body += proxy("analog", "Axis", "Stick", 0) + proxy("analog", "Other Axis", "Other", 0)
    with JoydevEmulator(other_fifo, scenario="motion", rate=500.0):
        emulator = JoydevEmulator(fifo, scenario="motion", rate=500.0).start()
        manager = build(body)
        stick, other = manager.device("Stick"), manager.device("Other")
        frames_until(manager, lambda: stick.store.total() > 20)
        emulator.stop()
        frames_until(manager, lambda: manager.status("Stick").state == "faulted")
        status = manager.status("Stick")
        assert status.reason and status.code == "DRV042" and status.stats.faults >= 1
        other_before, failed_at = other.store.total(), stick.error_at
        # away for a while: a restart attempt fails (renewing the fault's time); waited for
        frames_until(manager, lambda: stick.error_at != failed_at, timeout=10.0)
        assert manager.status("Stick").state in ("faulted", "reconnecting")
        # the other device went on meanwhile (waited for: a loaded machine may starve it a while)
        frames_until(manager, lambda: other.store.total() > other_before + 100, timeout=10.0)

        with JoydevEmulator(fifo, scenario="motion", rate=500.0):
            before = stick.store.total()
            resumed = frames_until(manager, lambda: stick.store.total() > before + 5, timeout=4.0)
            assert resumed < 2.0
            frames_until(manager, lambda: manager.proxy("Axis").timestamp is not None)
            assert manager.status("Stick").state == "running" and stick.restarts >= 1
        assert other.faults == 0


def test_an_unplugged_device_file_is_reopened(tmp_path: Path, build) -> None:
    body = joystick("Stick", tmp_path / "js0") + proxy("analog", "Axis", "Stick", 0)
    with JoydevEmulator(
        directory=tmp_path, scenario="disconnect", rate=1000.0, disconnect_after=30
    ) as emu:
        manager = build(body)
        stick = manager.device("Stick")
        frames_until(manager, lambda: emu.connections >= 3 and stick.restarts >= 2)
    assert stick.faults >= 2 and stick.store.total() > 60


# -- configuration problems ----------------------------------------------------------------------


def test_unusable_elements_stay_pending_with_a_reason(tmp_path: Path) -> None:
    path = tmp_path / "bad.jconf"
    path.write_text(
        configuration(
            "LinuxJoydev_drv",
            '<linux_joydev name="Empty" version="1"><port_name></port_name></linux_joydev>\n'
            + joystick("Negative", tmp_path / "js0", "<axis_buttons>-1</axis_buttons>")
            + joystick("Missing", tmp_path / "nothing-here"),
        )
    )
    reasons = pending_in(path)
    assert reasons["Empty"] == "port_name is empty"
    assert "axis_buttons: -1" in reasons["Negative"]
    assert "failed to start" in reasons["Missing"] and "nothing-here" in reasons["Missing"]


# -- the corpus example and ours -------------------------------------------------------------------


@pytest.fixture
def corpus_config(tmp_path: Path) -> Path:
    """VR Juggler's example.linux_joydev.jconf with only its port_name pointing at a FIFO."""
    path = corpus_copy(
        "example.linux_joydev.jconf",
        tmp_path,
        ("<port_name>/dev/input/js0</port_name>", f"<port_name>{tmp_path / 'js0'}</port_name>"),
    )
    return path


def test_the_corpus_example_delivers_through_its_proxies_and_aliases(
    tmp_path: Path, build, corpus_config: Path
) -> None:
    with JoydevEmulator(directory=tmp_path, scenario="buttons", rate=500.0):
        manager = build(corpus_config)
        toggled: set[int] = set()
        axes: dict[int, set[float]] = {a: set() for a in range(6)}

        def everything() -> bool:
            toggled.update(
                b for b in range(12) if manager.proxy(f"VJButton{b}").data == DigitalState.TOGGLE_ON
            )
            for a in range(6):
                axes[a].add(manager.proxy(f"VJAxis{a}").data)
            return len(toggled) == 12 and all({0.0, 0.5, 1.0} <= v for v in axes.values())

        frames_until(manager, everything)
        statuses = {s.name: s.state for s in manager.statuses()}
    assert statuses["Logitech Dual Action"] == "running"
    assert all(statuses[f"DigitalProxy{b}"] == "active" for b in range(12))


def test_monitor_shows_samples_of_the_corpus_example(tmp_path: Path, corpus_config: Path) -> None:
    with JoydevEmulator(directory=tmp_path, scenario="motion", rate=200.0):
        result, records = monitor_ndjson(
            corpus_config, duration=1, timeout=60, env={"NO_COLOR": "1"}
        )
    assert result.returncode == 0, result.stderr[-2000:]
    samples = samples_of(records, "Logitech Dual Action")
    assert samples, records[:5]
