"""TUIO through the input manager against the emulator's TUIO 1.1 traffic (issue 23 item 7,
issue 24 items 5 and 6): ``source`` messages are valid, two sources on one port keep their own
fingers (no slot flickers), late bundles change nothing, a flood of malformed datagrams is
counted bad one for one and shows the device ``undecodable``, bundles nested too deep are bad
datagrams rather than a fault, and nothing a peer sends reaches the terminal."""

from __future__ import annotations

import logging
import socket
import struct
from pathlib import Path

import pytest
from TUIO_drv.emulator import TuioEmulator, osc_bundle, osc_message

from gadgetctl.input import DeviceKind
from gadgetctl.input.testing import frame_recorder, frames_until, wait_until
from gadgetctl.input.testing.commands import run_gadgetctl
from gadgetctl.input.testing.configs import configuration, free_udp_port
from gadgetctl.input.testing.fixtures import managers_fixture
from gadgetctl.input.testing.floods import DatagramSender, bad_one_for_one

pytestmark = pytest.mark.timeout(60)

RATE = 200.0
build = managers_fixture("TUIO_drv", name="build", ready=True)


def table(name: str, port: int, points: int = 6) -> str:
    return f'<TUIO_drv name="{name}" version="1"><points>{points}</points><port>{port}</port></TUIO_drv>\n'


def test_two_sources_on_one_port_keep_their_own_fingers(build) -> None:
    port = free_udp_port()
    manager = build(table("T", port))
    frame, digital, analog = frame_recorder(manager, "T", DeviceKind.DIGITAL, DeviceKind.ANALOG)
    device = manager.device("T")
    with TuioEmulator(port, scenario="idle", rate=RATE, cursors=2, sources=2) as emu:
        # both sources send sessions 1 and 2: four fingers, never two
        frames_until(manager, lambda: device.store.latest(DeviceKind.DIGITAL).values[3] == 1)
        digital.clear()
        analog.clear()
        assert wait_until(lambda: len(digital) >= 100, 10.0, frame)
    assert all(list(d) == [1, 1, 1, 1, 0, 0] for d in digital), "a slot flickered"
    assert len({tuple(a) for a in analog}) == 1, "positions jumped between the sources"
    counters = device.counters
    assert counters["bad_records"] == 0 and counters["bad_datagrams"] == 0  # source is valid
    assert emu.frames_sent > 0 and device.store.total(DeviceKind.DIGITAL) > 0


def test_late_bundles_change_nothing(build) -> None:
    port = free_udp_port()
    manager = build(table("T", port))
    frame, digital = frame_recorder(manager, "T", DeviceKind.DIGITAL)
    device = manager.device("T")
    with TuioEmulator(port, scenario="idle", rate=RATE, cursors=2, late_every=2) as emu:
        frames_until(manager, lambda: device.store.latest(DeviceKind.DIGITAL).values[1] == 1)
        digital.clear()
        assert wait_until(lambda: device.counters["late_frames"] >= 20, 10.0, frame)
    assert emu.late_sent >= 20
    assert digital and all(list(d)[:2] == [1, 1] for d in digital), "a late bundle lifted a finger"
    assert device.counters["bad_records"] == 0


def test_a_flood_of_malformed_datagrams_is_counted_bad_one_for_one(build) -> None:
    port = free_udp_port()
    manager = build(table("T", port))
    junk = [
        b"\xff" + bytes(13),  # not OSC
        osc_message("/tuio/2Dcur", "set", "x")[:-2],  # cut off
        osc_message("/tuio/2Dcur", "alive", 1.5),  # OSC, but its only cursor message is bad
    ]
    counters = bad_one_for_one(manager, "T", port, [junk[n % 3] for n in range(3000)])
    assert counters["bad_datagrams"] > 0 and counters["decoded"] == 0
    status = manager.status("T")
    assert status.state == "undecodable" and status.code == "DRV045", status
    assert "none decoded; first: " in status.reason


def test_bundles_nested_too_deep_are_bad_datagrams_not_faults(build) -> None:
    port = free_udp_port()
    manager = build(table("T", port))
    deep = osc_message("/tuio/2Dcur", "fseq", 1)
    for _ in range(1100):  # about 22 KB (issue 24 item 5: RecursionError, a fault per datagram)
        deep = b"#bundle\x00" + bytes(8) + struct.pack(">i", len(deep)) + deep
    device = manager.device("T")
    bad_one_for_one(manager, "T", port, [deep] * 5)
    assert device.faults == 0 and manager.status("T").state == "undecodable"
    with TuioEmulator(port, scenario="idle", rate=RATE, cursors=1):
        frames_until(manager, lambda: manager.status("T").state == "running")


def test_nothing_a_peer_sends_is_logged(build, caplog) -> None:
    port = free_udp_port()
    manager = build(table("T", port))
    # type tags ESC, BEL, CR: python-osc logged each one, raw, through the root logger
    hostile = osc_bundle(b"/tuio/2Dcur\x00" + b",\x1b\x07\r\x00\x00\x00\x00" + bytes(4))
    with caplog.at_level(logging.DEBUG):
        bad_one_for_one(manager, "T", port, [hostile] * 10)
    assert caplog.records == []
    error = manager.device("T").health()["decode_error"]
    assert "\x1b" not in manager.status("T").reason and "\\x1b" in manager.status("T").reason
    assert "\x1b" in error or "\\x1b" in error  # the text as decoded, escaped where shown


def test_monitor_says_the_source_is_undecodable_and_keeps_the_terminal_clean(
    tmp_path: Path,
) -> None:
    port = free_udp_port()
    config = tmp_path / "tuio.jconf"
    config.write_text(configuration("TUIO_drv", table("T", port)))
    hostile = osc_message("/tuio/2Dcur", "alive")[:12] + b",\x1b]0;pwned\x07\x00"
    with DatagramSender(port, lambda n: hostile, interval=0.002) as sender:
        done = run_gadgetctl("monitor", str(config), "--duration", "1.5", "--format", "table")
    assert sender.sent > 0
    assert done.returncode == 1, done.stderr[-2000:]
    assert "\x1b" not in done.stderr and "\x07" not in done.stderr and "\x1b" not in done.stdout
    problems = [line for line in done.stderr.splitlines() if "problem" in line]
    assert len(problems) == 1 and problems[0].startswith("gadgetctl: problem: T: undecodable: ")
    assert "first: not OSC: type tag '\\x1b' is not one this decoder reads" in problems[0]


def test_the_sender_is_told_apart_by_its_address(build) -> None:
    """TUIO 1.0 senders name no source: two of them on one port are two sources all the same."""
    port = free_udp_port()
    manager = build(table("T", port))
    device = manager.device("T")
    udp = (socket.AF_INET, socket.SOCK_DGRAM)
    with socket.socket(*udp) as one, socket.socket(*udp) as other:
        for fseq in (1, 2, 3):
            for sender, session in ((one, 1), (other, 9)):
                alive = osc_message("/tuio/2Dcur", "alive", session)
                frame = osc_bundle(alive, osc_message("/tuio/2Dcur", "fseq", fseq))
                sender.sendto(frame, ("127.0.0.1", port))
    frames_until(manager, lambda: device.counters["decoded"] == 6)
    assert list(device.store.latest(DeviceKind.DIGITAL).values) == [1, 1, 0, 0, 0, 0]
    assert device.counters["late_frames"] == 0
