"""A port that never runs dry (/dev/zero, a flood of junk): each read is bounded, junk is
skipped in whole runs, and the monitor's --duration still ends on time."""

from __future__ import annotations

from pathlib import Path

import pytest
from LinuxJoydev_drv.standalone import (
    EVENT_SIZE,
    JS_EVENT_AXIS,
    JS_EVENT_BUTTON,
    JS_EVENT_INIT,
    EventDecoder,
    JoystickEvent,
    LinuxJoydevStandalone,
)

from gadgetctl.input.testing.commands import monitor_ndjson
from gadgetctl.input.testing.configs import rewritten

pytestmark = pytest.mark.timeout(30)
EXAMPLE = Path(__file__).resolve().parents[1] / "example.jconf"


def test_dev_zero_gives_bounded_reads_and_no_events() -> None:
    with LinuxJoydevStandalone("/dev/zero", connect_timeout=0.0) as joystick:
        for call in range(1, 4):
            sample = joystick.sample()  # used to read /dev/zero for ever
            assert sample.events == () and sample.buttons == () and sample.axes == ()
            assert joystick.skipped_bytes <= call * joystick.max_read
        assert joystick.skipped_bytes >= 2 * joystick.max_read - EVENT_SIZE


def test_records_after_a_megabyte_of_junk_are_found() -> None:
    decoder = EventDecoder(clock=lambda: 0.0)
    burst = [JoystickEvent(100, 0, JS_EVENT_BUTTON | JS_EVENT_INIT, 0)]
    burst += [JoystickEvent(100, 5, JS_EVENT_AXIS | JS_EVENT_INIT, 0)]
    junk = bytes(1 << 20) + b"\x05\x07" * 1000  # zeros, then bytes that are no type either
    events = decoder.feed(junk + b"".join(e.pack() for e in burst))
    assert events == burst
    assert decoder.skipped_bytes == len(junk) and decoder.resyncs == 1


def test_monitor_duration_is_kept_with_dev_zero_as_port(tmp_path: Path) -> None:
    config = rewritten(
        EXAMPLE,
        tmp_path,
        ("<port_name>/tmp/gadgetctl-js0</port_name>", "<port_name>/dev/zero</port_name>"),
    )
    result, records = monitor_ndjson(config, duration=1, timeout=25)
    assert result.returncode == 0, result.stderr[-2000:]
    stats = next(r for r in records if r["type"] == "stats")["devices"]["Joystick"]
    assert stats["state"] == "running" and stats["faults"] == 0 and stats["count"] == 0
