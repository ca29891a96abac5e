"""The joydev driver against its FIFO emulator, and against records a test writes itself."""

from __future__ import annotations

import os
import struct
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from LinuxJoydev_drv.emulator import (
    AXIS_HIGH,
    AXIS_LOW,
    JoydevEmulator,
    buttons_script,
    main,
    motion_axis_value,
)
from LinuxJoydev_drv.standalone import (
    EVENT_SIZE,
    JS_EVENT_AXIS,
    JS_EVENT_BUTTON,
    JS_EVENT_INIT,
    JoystickDisconnected,
    JoystickEvent,
    JoystickSample,
    LinuxJoydevStandalone,
    axis_button_pair,
    axis_buttons_state,
    normalize_axis,
)

pytestmark = pytest.mark.timeout(10)

INIT_BUTTON = JS_EVENT_BUTTON | JS_EVENT_INIT
INIT_AXIS = JS_EVENT_AXIS | JS_EVENT_INIT
T0 = 5_000_000  # a kernel-like time base, in ms


def record(time_ms: int, value: int, kind: int, number: int) -> bytes:
    return struct.pack("=IhBB", time_ms, value, kind, number)


def init_burst(buttons: list[int], axes: list[int], time_ms: int = T0) -> bytes:
    data = b"".join(record(time_ms, v, INIT_BUTTON, i) for i, v in enumerate(buttons))
    return data + b"".join(record(time_ms, v, INIT_AXIS, i) for i, v in enumerate(axes))


def as_tuples(events: list[JoystickEvent]) -> list[tuple[int, int, int, int]]:
    return [(e.time_ms, e.value, e.type, e.number) for e in events]


def collect(
    driver: LinuxJoydevStandalone,
    done: Callable[[list[JoystickEvent]], bool],
    timeout: float = 3.0,
) -> tuple[list[JoystickEvent], JoystickSample]:
    """Sample until ``done(events)`` holds; fails after ``timeout`` seconds."""
    events: list[JoystickEvent] = []
    end = time.monotonic() + timeout
    sample = driver.state()
    while not done(events):
        assert time.monotonic() < end, f"timed out with {len(events)} events"
        sample = driver.sample()
        events.extend(sample.events)
    return events, sample


@pytest.fixture
def fifo(tmp_path: Path) -> Path:
    path = tmp_path / "js0"
    os.mkfifo(path)
    return path


@pytest.fixture
def device(fifo: Path) -> Iterator[tuple[LinuxJoydevStandalone, int]]:
    """A driver on a FIFO and the write end that the test plays the kernel with."""
    driver = LinuxJoydevStandalone(fifo, axis_buttons=[4, 5], poll_timeout=0.2)
    driver.open()
    writer = os.open(fifo, os.O_WRONLY)  # does not block: the reader is open
    yield driver, writer
    driver.close()
    try:
        os.close(writer)
    except OSError:
        pass


# -- pure helpers --------------------------------------------------------------------------------


def test_normalize_axis_clamps_and_scales() -> None:
    assert normalize_axis(AXIS_HIGH) == 1.0
    assert normalize_axis(AXIS_LOW) == 0.0
    assert normalize_axis(0) == 0.5
    assert normalize_axis(-32768) == 0.0  # the raw s16 minimum is clamped
    assert normalize_axis(5, minimum=0, maximum=10) == 0.5
    with pytest.raises(ValueError):
        normalize_axis(0, minimum=1, maximum=1)


def test_axis_button_pair_has_no_dead_zone() -> None:
    assert axis_button_pair(0) == (0, 0)
    assert axis_button_pair(1) == (0, 1)
    assert axis_button_pair(-1) == (1, 0)
    assert axis_buttons_state([0, AXIS_HIGH, AXIS_LOW], [2, 1, 9]) == (1, 0, 0, 1, 0, 0)


# -- records written by the test ---------------------------------------------------------------


def test_init_burst_then_live_records(device: tuple[LinuxJoydevStandalone, int]) -> None:
    driver, writer = device
    assert driver.version is None and driver.name is None  # the ioctls fail on a FIFO
    os.write(writer, init_burst([0] * 12, [0] * 6))
    os.write(writer, record(T0 + 10, 1, JS_EVENT_BUTTON, 3))
    os.write(writer, record(T0 + 11, AXIS_HIGH, JS_EVENT_AXIS, 0))
    os.write(writer, record(T0 + 12, AXIS_LOW, JS_EVENT_AXIS, 1))
    os.write(writer, record(T0 + 13, 0, JS_EVENT_AXIS, 2))
    os.write(writer, record(T0 + 14, AXIS_LOW, JS_EVENT_AXIS, 4))
    os.write(writer, record(T0 + 15, 1, JS_EVENT_AXIS, 5))
    events, sample = collect(driver, lambda ev: len(ev) >= 24)
    assert len(events) == 24 and sum(e.is_init for e in events) == 18
    assert len(sample.buttons) == 12 and len(sample.axes) == 6  # counts grown from the burst
    assert sample.buttons[3] == 1 and sum(sample.buttons) == 1
    assert sample.normalized()[:3] == (1.0, 0.0, 0.5)
    # axis_buttons = [4, 5]: (low, high) of axis 4 at 12/13, of axis 5 at 14/15
    assert sample.virtual_buttons == (1, 0, 0, 1)
    assert sample.digital == (*sample.buttons, 1, 0, 0, 1)
    assert sample.time_ms == T0 + 15


def test_press_and_release_in_one_read_are_both_reported(
    device: tuple[LinuxJoydevStandalone, int],
) -> None:
    driver, writer = device
    os.write(writer, init_burst([0, 0], [0]))
    collect(driver, lambda ev: len(ev) >= 3)
    os.write(writer, record(T0 + 1, 1, JS_EVENT_BUTTON, 1) + record(T0 + 2, 0, JS_EVENT_BUTTON, 1))
    events, sample = collect(driver, lambda ev: len(ev) >= 2)
    assert [(e.number, e.value) for e in events] == [(1, 1), (1, 0)]
    assert sample.buttons == (0, 0)


def test_garbage_and_a_cut_record_are_skipped(device: tuple[LinuxJoydevStandalone, int]) -> None:
    driver, writer = device
    os.write(writer, init_burst([0] * 4, [0] * 2))
    collect(driver, lambda ev: len(ev) >= 6)
    good = record(T0 + 20, 1234, JS_EVENT_AXIS, 1)
    cut = record(T0 + 21, 1, JS_EVENT_BUTTON, 2)[:5]
    os.write(writer, b"\xff\xfe\x07" + good + cut + record(T0 + 22, 1, JS_EVENT_BUTTON, 2))
    events, sample = collect(driver, lambda ev: len(ev) >= 2)
    assert as_tuples(events) == [
        (T0 + 20, 1234, JS_EVENT_AXIS, 1),
        (T0 + 22, 1, JS_EVENT_BUTTON, 2),
    ]
    assert driver.skipped_bytes == 3 + 5
    assert driver.resyncs == 2
    assert sample.axes == (0, 1234) and sample.buttons == (0, 0, 1, 0)


def test_a_cut_record_that_looks_whole_is_taken_back(
    device: tuple[LinuxJoydevStandalone, int],
) -> None:
    driver, writer = device
    os.write(writer, init_burst([0] * 2, [0] * 6))
    collect(driver, lambda ev: len(ev) >= 8)
    t = 0x004C4C02  # its low byte, 2, is a valid axis number
    cut = record(t, 1000, JS_EVENT_AXIS, 9)[:7]  # time, value and type: only the number is missing
    real = record(t, 555, JS_EVENT_AXIS, 0) + record(t + 1, 777, JS_EVENT_AXIS, 1)
    os.write(writer, cut + real)
    events, sample = collect(driver, lambda ev: len(ev) >= 2)
    assert as_tuples(events) == [(t, 555, JS_EVENT_AXIS, 0), (t + 1, 777, JS_EVENT_AXIS, 1)]
    assert sample.axes == (555, 777, 0, 0, 0, 0)  # the fake "axis 2 = 1000" was withdrawn
    assert driver.skipped_bytes == 7 and driver.resyncs == 1


def test_unknown_controls_are_rejected(device: tuple[LinuxJoydevStandalone, int]) -> None:
    driver, writer = device
    os.write(writer, init_burst([0] * 2, [0] * 2))
    collect(driver, lambda ev: len(ev) >= 4)
    # live records may not add controls, and button values are 0 or 1
    os.write(writer, record(T0 + 1, 1, JS_EVENT_BUTTON, 7) + record(T0 + 2, 5, JS_EVENT_BUTTON, 0))
    os.write(writer, record(T0 + 3, 99, JS_EVENT_AXIS, 1))
    events, sample = collect(driver, lambda ev: len(ev) >= 1)
    assert as_tuples(events) == [(T0 + 3, 99, JS_EVENT_AXIS, 1)]
    assert driver.skipped_bytes == 2 * EVENT_SIZE
    assert len(sample.buttons) == 2


def test_truncated_tail_then_end_of_file(device: tuple[LinuxJoydevStandalone, int]) -> None:
    driver, writer = device
    os.write(writer, init_burst([1], [7]) + record(T0 + 5, 0, JS_EVENT_BUTTON, 0)[:6])
    os.close(writer)
    _, sample = collect(driver, lambda ev: len(ev) >= 2)
    # the records before the end are delivered; the end comes with the next call
    assert sample.buttons == (1,) and sample.axes == (7,)
    assert driver.skipped_bytes == 6
    with pytest.raises(JoystickDisconnected):
        driver.sample()
    with pytest.raises(JoystickDisconnected):
        driver.sample()


def test_fifo_without_writer_reports_disconnect_after_timeout(fifo: Path) -> None:
    with LinuxJoydevStandalone(fifo, connect_timeout=5.0, poll_timeout=0.01) as driver:
        assert driver.sample().events == ()  # no writer yet: nothing, not an error
        driver.connect_timeout = 0.05
        end = time.monotonic() + 2.0
        with pytest.raises(JoystickDisconnected):
            while time.monotonic() < end:
                driver.sample()


def test_configured_counts_size_the_state(fifo: Path) -> None:
    with LinuxJoydevStandalone(fifo, num_buttons=12, num_axes=6, axis_buttons=[1]) as driver:
        state = driver.state()
        assert state.buttons == (0,) * 12 and state.axes == (0,) * 6
        assert state.virtual_buttons == (0, 0)
        assert state.normalized() == (0.5,) * 6


def test_injected_file_object_is_not_closed() -> None:
    read_fd, write_fd = os.pipe()
    with open(read_fd, "rb", buffering=0) as stream:
        driver = LinuxJoydevStandalone(stream, poll_timeout=0.2)
        driver.open()
        os.write(write_fd, init_burst([0, 1], [AXIS_LOW]))
        os.close(write_fd)
        _, sample = collect(driver, lambda ev: len(ev) >= 3)
        assert sample.buttons == (0, 1) and sample.normalized() == (0.0,)
        with pytest.raises(JoystickDisconnected):
            driver.sample()
        driver.close()
        assert not stream.closed


def test_sample_needs_open(fifo: Path) -> None:
    with pytest.raises(RuntimeError):
        LinuxJoydevStandalone(fifo).sample()


# -- the emulator ------------------------------------------------------------------------------


def test_emulator_buttons_scenario(tmp_path: Path) -> None:
    with (
        JoydevEmulator(directory=tmp_path, scenario="buttons", rate=1000.0) as emu,
        LinuxJoydevStandalone(emu.address, poll_timeout=0.05) as driver,
    ):
        cycle = buttons_script(12, 6)
        n_live = sum(len(step) for step in cycle)
        events, _ = collect(driver, lambda ev: len(ev) >= 18 + n_live)
        burst, live = events[:18], events[18 : 18 + n_live]
        assert [(e.type, e.number, e.value) for e in burst] == (
            [(INIT_BUTTON, i, 0) for i in range(12)] + [(INIT_AXIS, i, 0) for i in range(6)]
        )
        assert [(e.type, e.number, e.value) for e in live] == [ev for step in cycle for ev in step]
        # every button toggles on, then off, in order
        presses = [(e.number, e.value) for e in live if e.is_button]
        assert presses == [(b, v) for b in range(12) for v in (1, 0)]
        times = [e.time_ms for e in events]
        assert times == sorted(times)
        assert driver.skipped_bytes == 0


def test_emulator_axis_buttons_follow_the_sweep(tmp_path: Path) -> None:
    with (
        JoydevEmulator(
            directory=tmp_path, scenario="buttons", rate=400.0, buttons=2, axes=2
        ) as emu,
        LinuxJoydevStandalone(emu.address, poll_timeout=0.05, axis_buttons=[1]) as driver,
    ):
        seen: set[tuple[int, tuple[int, int]]] = set()
        end = time.monotonic() + 3.0
        while len(seen) < 3:
            assert time.monotonic() < end, seen
            sample = driver.sample()
            if len(sample.axes) > 1:
                assert sample.virtual_buttons == axis_button_pair(sample.axes[1])
            if sample.events and sample.events[-1].is_axis and sample.events[-1].number == 1:
                seen.add((sample.axes[1], sample.virtual_buttons))
        assert seen == {(AXIS_LOW, (1, 0)), (0, (0, 0)), (AXIS_HIGH, (0, 1))}


def test_emulator_idle_sends_only_the_initial_burst(tmp_path: Path) -> None:
    with (
        JoydevEmulator(directory=tmp_path, scenario="idle", rate=1000.0) as emu,
        LinuxJoydevStandalone(emu.address, poll_timeout=0.02) as driver,
    ):
        events, _ = collect(driver, lambda ev: len(ev) >= 18)
        end = time.monotonic() + 0.05
        while time.monotonic() < end:
            events.extend(driver.sample().events)
        assert len(events) == 18 and all(e.is_init for e in events)


def test_emulator_motion_values(tmp_path: Path) -> None:
    rate = 1000.0
    with (
        JoydevEmulator(directory=tmp_path, scenario="motion", rate=rate) as emu,
        LinuxJoydevStandalone(emu.address, poll_timeout=0.05) as driver,
    ):
        events, sample = collect(driver, lambda ev: len(ev) >= 18 + 200)
        assert as_tuples(events) == emu.sent_events()[: len(events)]
        for event in events[18:]:
            tick = round((event.time_ms - emu.time_base_ms) * rate / 1000.0)
            assert event.value == motion_axis_value(tick, event.number, 6)
        assert all(0.0 <= v <= 1.0 for v in sample.normalized())


def test_emulator_garbage_is_counted_and_the_stream_recovers(tmp_path: Path) -> None:
    with (
        JoydevEmulator(directory=tmp_path, scenario="garbage", rate=2000.0, seed=3) as emu,
        LinuxJoydevStandalone(emu.address, poll_timeout=0.05) as driver,
    ):
        events, _ = collect(driver, lambda ev: len(ev) >= 18 + 300)
        assert as_tuples(events) == emu.sent_events()[: len(events)]
        assert driver.skipped_bytes > 0
        assert driver.resyncs >= 20


def test_emulator_disconnect_then_reconnect(tmp_path: Path) -> None:
    with JoydevEmulator(
        directory=tmp_path, scenario="disconnect", rate=1000.0, disconnect_after=10
    ) as emu:
        driver = LinuxJoydevStandalone(emu.address, poll_timeout=0.05)
        driver.open()
        events: list[JoystickEvent] = []
        end = time.monotonic() + 3.0
        with pytest.raises(JoystickDisconnected):
            while time.monotonic() < end:
                events.extend(driver.sample().events)
        assert sum(not e.is_init for e in events) == 10
        last = driver.state()
        driver.close()

        driver.open()  # the emulator "replugged" a new device node at the same path
        again, _ = collect(driver, lambda ev: len(ev) >= 18)
        burst = again[:18]  # live records may follow in the same read
        assert all(e.is_init for e in burst)
        assert tuple(e.value for e in burst if e.is_button) == last.buttons
        assert tuple(e.value for e in burst if e.is_axis) == last.axes
        driver.close()
        assert emu.connections == 2


def test_emulator_main_runs_for_a_duration(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "js7"
    assert main(["--scenario", "idle", "--duration", "0.05", "--path", str(path)]) == 0
    assert f"<port_name>{path}</port_name>" in capsys.readouterr().out
    assert not path.exists()


def test_emulator_rejects_unknown_scenario() -> None:
    with pytest.raises(ValueError):
        JoydevEmulator(scenario="dance")
