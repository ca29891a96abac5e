"""No silent loss for OptiTrack (issue 23, items 1, 4 and 9): a flood of malformed datagrams
is counted as bad one for one, frames that do not decode (here: NatNet 3.0 frames read as the
2.0 the element names, upstream's "rigid body marker count 973541338" case) show the device
``undecodable`` (DRV045) with the first error instead of ``running``, and ``monitor`` ends
with exit status 1 saying so."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest
from OptiTrack_drv.emulator import FrameWriter, OptiTrackEmulator
from OptiTrack_drv.tests.elements import optitrack_element

from gadgetctl.input.testing import frames_until
from gadgetctl.input.testing.commands import run_gadgetctl
from gadgetctl.input.testing.configs import configuration, free_udp_port
from gadgetctl.input.testing.fixtures import managers_fixture
from gadgetctl.input.testing.floods import DatagramSender, bad_one_for_one

pytestmark = pytest.mark.timeout(90)

build = managers_fixture("Optitrack_drv", name="build", ready=True)


def element(port: int, version: str) -> str:
    return optitrack_element(
        "OT", [1], [], f"<port>{port}</port><natnet_version>{version}</natnet_version>"
    )


def malformed(n: int) -> bytes:
    """No NatNet message: a junk id, a frame cut short, a count beyond the limits."""
    good = FrameWriter("motion", 2, 2, version=(4, 1)).frame(n)
    count = struct.pack("<HHiii", 7, 16, n, 0, 0) + struct.pack("<i", 1_000_000)
    return (b"\x7a\x7a\x00\x00junk", good[: len(good) // 2], count)[n % 3]


def test_a_flood_of_malformed_datagrams_is_counted_bad_one_for_one(build) -> None:
    port = free_udp_port()
    manager = build(element(port, "4.1"))
    counters = bad_one_for_one(manager, "OT", port, [malformed(n) for n in range(3000)])
    assert counters["datagrams"] == counters["bad_datagrams"] > 0
    status = manager.status("OT")
    assert status.state == "undecodable" and status.code == "DRV045"
    assert status.reason.startswith(f"{counters['bad_datagrams']} bad datagrams, none decoded")
    assert status.reason.endswith("; first: message id 31354 is no NatNet message")
    with OptiTrackEmulator(port, scenario="motion", rate=200.0):  # a real server: running again
        frames_until(manager, lambda: manager.status("OT").state == "running")


@pytest.mark.parametrize("view", ["table", "events"])
def test_monitor_exits_1_with_the_reason_when_no_frame_decodes(tmp_path: Path, view: str) -> None:
    port = free_udp_port()
    config = tmp_path / "ot.jconf"
    config.write_text(configuration("Optitrack_drv", element(port, "2.0")))
    frames = FrameWriter("motion", 2, 2, version=(3, 0))
    with DatagramSender(port, frames.frame, interval=0.005) as sender:
        done = run_gadgetctl("monitor", str(config), "--duration", "1.5", "--format", view)
    assert sender.sent > 0
    assert done.returncode == 1, done.stderr[-2000:]
    problems = [line for line in done.stderr.splitlines() if "problem" in line]
    assert len(problems) == 1, done.stderr[-2000:]
    assert problems[0].startswith("gadgetctl: problem: OT: undecodable: ")
    assert "none decoded; first: NatNet 2.0 frame: rigid body marker count" in problems[0]
    if view == "table":
        assert "  undecodable  " in done.stdout
    else:
        assert "  OT  status  undecodable: " in done.stdout
