"""The TUIO driver against its loopback emulator: touch slots appearing and leaving, x and y
through analog proxies, the upstream crashes fixed (unknown session, bare message), garbage,
disconnection and return; the plug-in needs no python-osc."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from pythonosc.osc_message_builder import OscMessageBuilder
from TUIO_drv.emulator import TuioEmulator, cursor_position, frame_bundle, message
from TUIO_drv.osc import OscMessage
from TUIO_drv.standalone import MAX_ALIVE, SOURCE_FRAMES, TouchSlots, TuioReceiver

from gadgetctl.input import DeviceKind, DigitalState
from gadgetctl.input.testing import frames_until
from gadgetctl.input.testing.commands import run_gadgetctl
from gadgetctl.input.testing.configs import configuration, free_udp_port, proxy
from gadgetctl.input.testing.fixtures import managers_fixture

pytestmark = pytest.mark.timeout(30)

RATE = 200.0
PRESSED = (DigitalState.ON, DigitalState.TOGGLE_ON)
RELEASED = (DigitalState.OFF, DigitalState.TOGGLE_OFF)


build = managers_fixture("TUIO_drv", name="build", ready=True)


def table(name: str, port: int, points: int = 4) -> str:
    return f'<TUIO_drv name="{name}" version="1"><points>{points}</points><port>{port}</port></TUIO_drv>\n'


# -- the protocol ------------------------------------------------------------------------------


def test_new_sessions_take_the_lowest_free_slot_and_leave() -> None:
    slots = TouchSlots(3)
    slots.apply("/tuio/2Dcur", ["alive", 7, 9])
    slots.apply("/tuio/2Dcur", ["set", 9, 0.25, 0.75, 0.0, 0.0, 0.0])
    assert slots.digital() == [1, 1, 0] and slots.analog()[2:4] == [0.25, 0.75]
    slots.apply("/tuio/2Dcur", ["alive", 9])  # 7 lifts: slot 0 frees
    slots.apply("/tuio/2Dcur", ["alive", 9, 11, 12, 13])  # 11 takes slot 0, 12 slot 2, 13 none
    assert slots.digital() == [1, 1, 1] and slots.overflow_sessions == 1
    assert slots.analog()[2:4] == [0.25, 0.75]  # 9 stayed in slot 1


def test_unknown_sessions_and_bad_arguments_are_counted_not_fatal() -> None:
    slots = TouchSlots(2)
    slots.apply("/tuio/2Dcur", ["set", 5, 0.5, 0.5, 0.0, 0.0, 0.0])  # upstream: null dereference
    slots.apply("/tuio/2Dcur", ["set", "x", 0.5])
    slots.apply("/tuio/2Dcur", ["alive", *range(MAX_ALIVE + 1)])
    slots.apply("/tuio/2Dcur", [])
    slots.apply("/tuio/2Dobj", ["alive"])
    assert (slots.unknown_sessions, slots.bad_records, slots.other_messages) == (1, 3, 1)
    assert slots.digital() == [0, 0]


def test_a_bare_message_is_decoded_like_a_bundle() -> None:
    receiver = TuioReceiver(0, 2)
    assert receiver.feed(message("alive", 3))  # upstream threw on non-bundles
    assert receiver.feed(frame_bundle(1, 2, "idle", source=None))  # the same (unnamed) source
    assert not receiver.feed(b"\x00\x01garbage")
    assert receiver.ledger.bad_count == 1 and receiver.slots.digital() == [1, 1]
    assert receiver.slots.sessions == 2  # session 3 lifted: the bundle's alive lists 1 and 2
    nested = OscMessageBuilder("/tuio/2Dcur")
    nested.add_arg("fseq")
    nested.add_arg(2)
    assert not receiver.feed(nested.build().dgram)  # a frame number alone: good, no cursor data
    assert receiver.ledger.decoded_count == 3 and receiver.slots.bad_records == 0


# -- through the input manager -------------------------------------------------------------------


def test_touches_appear_and_leave_through_proxies(build) -> None:
    port = free_udp_port()
    body = table("T", port, points=4)
    for slot in range(3):
        body += proxy("digital", f"Touch {slot}", "T", slot)
    body += proxy("analog", "X0", "T", 0) + proxy("analog", "Y0", "T", 1)
    manager = build(body)
    seen: dict[int, set[str]] = {slot: set() for slot in range(3)}

    def both_ways() -> bool:
        for slot in range(3):
            data = manager.proxy(f"Touch {slot}").data
            seen[slot].add("down" if data in PRESSED else "up")
        return seen[0] == seen[1] == {"down", "up"}

    # two fingers at a time (the even ones, then the odd ones): slots 0 and 1, never slot 2
    with TuioEmulator(port, scenario="buttons", rate=RATE, cursors=4):
        frames_until(manager, both_ways, timeout=10.0)
    assert seen[2] == {"up"}
    store = manager.device("T").store
    assert len(store.latest(DeviceKind.DIGITAL).values) == 4
    assert len(store.latest(DeviceKind.ANALOG).values) == 8


def test_positions_reach_the_analog_proxies(build) -> None:
    port = free_udp_port()
    body = (
        table("T", port, points=4) + proxy("analog", "X2", "T", 4) + proxy("analog", "Y2", "T", 5)
    )
    manager = build(body)
    with TuioEmulator(port, scenario="idle", rate=RATE, cursors=3):
        frames_until(manager, lambda: manager.proxy("X2").raw not in (None, 0.0))
    x, y = cursor_position(0, 2, False)
    assert manager.proxy("X2").data == pytest.approx(x, abs=1e-6)
    assert manager.proxy("Y2").data == pytest.approx(y, abs=1e-6)


def test_garbage_is_counted_and_the_device_keeps_running(build) -> None:
    port = free_udp_port()
    manager = build(table("T", port, points=4) + proxy("digital", "Touch 0", "T", 0))
    dev = manager.device("T")
    with TuioEmulator(port, scenario="garbage", rate=RATE, cursors=2, max_frames=40) as emu:
        frames_until(manager, lambda: emu.finished.is_set() and dev.counters["datagrams"] >= 80)
        assert manager.status("T").state == "running" and dev.faults == 0
    # exact counts once sampling stopped: the last datagram is counted received before it is
    # counted bad, and this thread may read between the two
    manager.shutdown()
    counters = dev.counters
    assert counters["bad_datagrams"] == emu.garbage["bad_datagrams"] == 20
    assert counters["unknown_sessions"] == emu.garbage["unknown_sessions"] == 10
    assert counters["bad_records"] == 0
    assert manager.proxy("Touch 0").data in PRESSED


def test_a_silent_source_faults_and_data_returns_within_two_seconds(build) -> None:
    port = free_udp_port()
    manager = build(table("T", port) + proxy("digital", "Touch 0", "T", 0), peer_timeout=0.3)
    dev = manager.device("T")
    with TuioEmulator(port, scenario="disconnect", rate=RATE, disconnect_after=20) as emu:
        frames_until(manager, lambda: emu.finished.is_set() and dev.counters["datagrams"] >= 20)
        frames_until(manager, lambda: manager.status("T").state == "faulted")
    assert "TUIO" in manager.status("T").reason
    with TuioEmulator(port, scenario="motion", rate=RATE):
        count = dev.store.total()
        resumed = frames_until(manager, lambda: dev.store.total() > count, timeout=4.0)
        assert resumed < 2.0
        frames_until(manager, lambda: manager.status("T").state == "running")
    assert dev.restarts >= 1


def test_the_plugin_loads_without_python_osc() -> None:
    script = (
        "import sys; sys.modules['pythonosc'] = None; "
        "from gadgetctl.cli.main import main; sys.argv = ['gadgetctl'] + sys.argv[1:]; main()"
    )
    loaded = subprocess.run(
        [sys.executable, "-c", script, "drivers", "load", "TUIO_drv", "--format", "json"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert loaded.returncode == 0, loaded.stdout + loaded.stderr
    (plugin,) = json.loads(loaded.stdout)["plugins"]
    assert not plugin["diagnostics"]


def test_validate_knows_the_units_of_points(tmp_path: Path) -> None:
    path = tmp_path / "units.jconf"
    body = (
        table("T", 3333, points=2) + proxy("digital", "D1", "T", 1) + proxy("digital", "D2", "T", 2)
    )
    body += proxy("analog", "A3", "T", 3) + proxy("analog", "A4", "T", 4)
    path.write_text(configuration("TUIO_drv", body))
    result = run_gadgetctl("validate", str(path), timeout=60)
    assert result.returncode == 1 and result.stdout.count("CFG034") == 2
    assert "'D2'" in result.stdout and "'A4'" in result.stdout
    assert "'D1'" not in result.stdout and "'A3'" not in result.stdout


def test_a_source_silent_for_the_timeout_is_forgotten_and_its_fingers_lift() -> None:
    """A TUIO 1.0 sender restarted from another port is another source: the old one's fingers
    must not stay down for ever; a reader that stalls and then reads its backlog forgets no
    one that is still sending."""
    slots = TouchSlots(3)
    alive = [OscMessage("/tuio/2Dcur", ("alive", 1))]
    slots.frame(alive, "127.0.0.1:5000", now=100.0)
    slots.frame(alive, "127.0.0.1:5002", now=100.0)
    for n in range(SOURCE_FRAMES):  # 30 frames of the restarted sender, within the timeout
        slots.frame(alive, "127.0.0.1:5001", now=100.0 + n * 0.01)
    assert slots.digital() == [1, 1, 1] and slots.forgotten_sources == 0
    # a reader stall of 10 s, then its backlog: 5000 (silent 10 s, 31 frames of others since)
    # is gone; 5001 was silent as long but only one frame came since: its frames are queued
    slots.frame(alive, "127.0.0.1:5002", now=110.0)
    assert slots.forgotten_sources == 1 and slots.digital() == [0, 1, 1]
    assert set(slots.sources) == {"127.0.0.1:5001", "127.0.0.1:5002"}
