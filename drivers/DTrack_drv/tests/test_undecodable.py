"""No silent loss (issue 23, items 4 and 9): a flood of malformed datagrams is counted as bad one
for one, a tracker whose every datagram fails to decode is shown ``undecodable`` (DRV045) with
the first error instead of ``running``, and ``monitor`` ends with exit status 1 saying so (the
kernel's drops: ``test_overflow.py``)."""

from __future__ import annotations

from pathlib import Path

import pytest
from DTrack_drv.emulator import DTrackEmulator

from gadgetctl.input.testing import frames_until
from gadgetctl.input.testing.commands import run_gadgetctl
from gadgetctl.input.testing.configs import configuration, free_udp_port
from gadgetctl.input.testing.fixtures import managers_fixture
from gadgetctl.input.testing.floods import DatagramSender, bad_one_for_one

pytestmark = pytest.mark.timeout(90)

build = managers_fixture("DTrack_drv", name="build", ready=True)


def tracker(name: str, port: int) -> str:
    return f'<dtrack name="{name}" version="1"><receive_port>{port}</receive_port></dtrack>\n'


def malformed(n: int) -> bytes:
    """Not one valid DTrack line: bad numbers, a cut body, bytes that are not ASCII."""
    return (b"fr x%d\r\n" % n, b"6d 1 [0 1.0][1 2", b"\xff\xfe\x00" * (n % 7 + 1))[n % 3]


def test_a_flood_of_malformed_datagrams_is_counted_bad_one_for_one(build) -> None:
    port = free_udp_port()
    manager = build(tracker("DT", port))
    counters = bad_one_for_one(manager, "DT", port, [malformed(n) for n in range(3000)])
    assert counters["datagrams"] == counters["bad_datagrams"] > 0
    status = manager.status("DT")
    assert status.state == "undecodable" and status.code == "DRV045"
    assert status.reason.startswith(f"{counters['bad_datagrams']} bad datagrams, none decoded")
    assert status.reason.endswith("; first: no valid DTrack line")
    with DTrackEmulator(port, scenario="motion", rate=200.0):  # a real tracker: running again
        frames_until(manager, lambda: manager.status("DT").state == "running")


@pytest.mark.parametrize("view", ["table", "events"])
def test_monitor_exits_1_with_the_reason_when_a_tracker_decoded_nothing(
    tmp_path: Path, view: str
) -> None:
    port = free_udp_port()
    config = tmp_path / "dt.jconf"
    config.write_text(configuration("DTrack_drv", tracker("DT", port)))
    with DatagramSender(port, malformed, interval=0.005) as sender:
        done = run_gadgetctl("monitor", str(config), "--duration", "1.5", "--format", view)
    assert sender.sent > 0
    assert done.returncode == 1, done.stderr[-2000:]
    problems = [line for line in done.stderr.splitlines() if "problem" in line]
    assert len(problems) == 1, done.stderr[-2000:]
    assert problems[0].startswith("gadgetctl: problem: DT: undecodable: ")
    assert "none decoded; first: no valid DTrack line" in problems[0]
    if view == "table":
        assert "  undecodable  " in done.stdout  # the status column
    else:
        assert "  DT  status  undecodable: " in done.stdout
