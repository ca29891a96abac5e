"""Why a device has no data, where the user looks (issue 25 items 1 and 4): the live view shows a
pending device's reason at 80x24 while it runs, its proxies point at it, and the end of a run
says each cause once, in one line naming the port or file, without the layers of wrapped
messages and ``[Errno N]`` the drivers' exceptions carry.
"""

from __future__ import annotations

import shlex
import socket
import subprocess
import sys
from pathlib import Path

import pytest
import serial
from tmux_pane import Pane

from conftest import REPO

pytestmark = pytest.mark.timeout(90)

PINCH_EXAMPLE = REPO / "drivers" / "PinchGlove_drv" / "example.jconf"
DTRACK_EXAMPLE = REPO / "drivers" / "DTrack_drv" / "example.jconf"


def pinch_config(tmp_path: Path) -> tuple[Path, Path]:
    """The PinchGlove example pointed at a serial port that does not exist."""
    port = tmp_path / "no-such-pinch-port"
    text = PINCH_EXAMPLE.read_text(encoding="utf-8").replace("/tmp/gadgetctl-pinch", str(port))
    assert str(port) in text
    config = tmp_path / "pinch.jconf"
    config.write_text(text, encoding="utf-8")
    return config, port


def monitor(*args: str | Path, timeout: float = 60) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "gadgetctl", "monitor", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=REPO,
    )


def test_the_live_view_shows_why_a_device_is_pending_at_80x24(tmp_path):
    config, port = pinch_config(tmp_path)
    command = " ".join(
        shlex.quote(str(a)) for a in (sys.executable, "-m", "gadgetctl", "monitor", config)
    )
    with Pane(command, cols=80, rows=24) as pane:
        pane.wait_for(r"^PinchGlove\s.*pending")
        # the reason, under the device, wrapped to the screen; the port named once
        # (the reason wraps wherever the port's length puts it: between any two words)
        shown = pane.wait_for(r"cannot\s+open\s(.|\n)*?No\s+such\s+file\s+or\s+directory").group(0)
        expected = f"cannot open {port}: No such file or directory"
        assert "".join(expected.split()) == "".join(shown.split())  # a long path wraps
        assert "Errno" not in pane.screen()
        # each proxy and alias says where its cause is instead of a bare "stupefied"
        assert "see PinchGlove" in pane.line(r"^  Left Glove Proxy\s+stupefied")
        assert "see PinchGlove" in pane.line(r"^  VJLeftGlove\s+stupefied")
        pane.keys("q", literal=True)
        pane.wait_for(r"EXIT=1")


def test_a_run_ends_with_one_line_per_cause(tmp_path):
    config, port = pinch_config(tmp_path)
    done = monitor(config, "--duration", "0.3", "--format", "table")
    assert done.returncode == 1
    problems = [line for line in done.stderr.splitlines() if line.startswith("gadgetctl: problem:")]
    assert problems == [
        f"gadgetctl: problem: PinchGlove: pending: the device failed to start: cannot open "
        f"{port}: No such file or directory (24 proxies and aliases reading it stupefied)"
    ]


def test_a_proxy_selected_without_its_device_keeps_its_own_reason(tmp_path):
    config, port = pinch_config(tmp_path)
    done = monitor(config, "VJLeftGlove", "--duration", "0.3", "--format", "table")
    assert done.returncode == 1
    problems = [line for line in done.stderr.splitlines() if line.startswith("gadgetctl: problem:")]
    assert len(problems) == 1
    assert problems[0].startswith("gadgetctl: problem: VJLeftGlove: stupefied: device 'PinchGlove'")
    assert problems[0].endswith(f"cannot open {port}: No such file or directory")


def test_a_taken_udp_port_is_named_once(tmp_path):
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        number = taken.getsockname()[1]
        text = DTRACK_EXAMPLE.read_text(encoding="utf-8")
        text = text.replace(
            "<receive_port>5000</receive_port>", f"<receive_port>{number}</receive_port>"
        )
        config = tmp_path / "dtrack.jconf"
        config.write_text(text, encoding="utf-8")
        done = monitor(config, "--duration", "0.3", "--format", "table")
    assert done.returncode == 1
    problems = [line for line in done.stderr.splitlines() if line.startswith("gadgetctl: problem:")]
    assert len(problems) == 1, done.stderr
    assert f"cannot bind UDP port {number}: Address already in use" in problems[0]
    assert "OSError" not in done.stderr and "Errno" not in done.stderr


def test_describe_gives_one_cause_for_a_wrapped_serial_error(tmp_path):
    from gadgetctl.input.errors import describe

    missing = tmp_path / "ttyNothing"
    try:
        try:
            serial.serial_for_url(str(missing))
        except serial.SerialException as err:
            raise ConnectionError(f"cannot open {missing}: {err}") from err
    except ConnectionError as err:
        assert describe(err) == f"cannot open {missing}: No such file or directory"
    try:
        missing.open()
    except OSError as err:
        assert describe(err) == f"{missing}: No such file or directory"
    assert describe(OSError("device unplugged")) == "OSError: device unplugged"
