"""`--duration` is seconds of wall clock on every command, whatever frame rate is reached
(issue 12 item 3); a frame rate that is not reached is said once and shown in the statistics.

The runs below ask for frame rates far beyond what the machine reaches, so that counting
frames instead of seconds would run for many times the duration. The pytest timeouts are
hang guards; nothing here measures speed.
"""

from __future__ import annotations

import os
import re
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import REPO

ALL_DEVICES = REPO / "examples" / "all_devices.jconf"
WAVEFORM = REPO / "examples" / "waveform.jconf"
FRAMES_LINE = re.compile(
    r"^frames: (\d+) in ([\d.]+) s, ([\d.]+) Hz achieved of ([\d.]+) Hz requested$", re.M
)

pytestmark = pytest.mark.timeout(120)


def gadgetctl(*args: str | Path, timeout: float = 90) -> subprocess.CompletedProcess:
    env = {**os.environ, "NO_COLOR": "1"}
    return subprocess.run(
        [sys.executable, "-m", "gadgetctl", *map(str, args)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
        stdin=subprocess.DEVNULL,
    )


def frames_of(result: subprocess.CompletedProcess) -> tuple[int, float, float, float]:
    found = FRAMES_LINE.search(result.stdout)
    assert found, result.stdout[-2000:] + result.stderr[-2000:]
    frames, seconds, achieved, requested = found.groups()
    return int(frames), float(seconds), float(achieved), float(requested)


def test_monitor_duration_is_seconds_when_the_frame_rate_is_not_reached() -> None:
    result = gadgetctl(
        "monitor", ALL_DEVICES, "--rate", "10000", "--duration", "1", "--format", "table", "--stats"
    )
    assert result.returncode == 0, result.stderr
    frames, seconds, achieved, requested = frames_of(result)
    assert requested == 10000 and frames < 10000  # the run ended on time, not on a frame count
    assert 1.0 <= seconds < 3.0
    assert achieved == pytest.approx(frames / seconds, rel=0.02)
    notes = [line for line in result.stderr.splitlines() if "not reached" in line]
    assert len(notes) == 1, result.stderr  # said once
    assert "10000 Hz is not reached" in notes[0]
    # the note is said once, when the shortfall shows; the statistics cover the whole run
    said = float(re.search(r"about (\d+) frames per second", notes[0]).group(1))
    assert said == pytest.approx(achieved, rel=0.25)


def test_ndjson_monitor_says_so_once_too() -> None:
    result = gadgetctl(
        "monitor", ALL_DEVICES, "--rate", "10000", "--duration", "1", "--format", "ndjson"
    )
    assert result.returncode == 0, result.stderr
    assert result.stderr.count("not reached") == 1, result.stderr
    assert result.stdout.rstrip().splitlines()[-1].startswith('{"v":1,"type":"end"')


def test_a_reached_frame_rate_says_nothing() -> None:
    result = gadgetctl(
        "monitor", WAVEFORM, "--rate", "5", "--duration", "1", "--format", "table", "--stats"
    )
    assert result.returncode == 0, result.stderr
    frames, seconds, _achieved, requested = frames_of(result)
    assert requested == 5 and seconds >= 1.0 and 4 <= frames <= 6
    assert "not reached" not in result.stderr


def test_replay_duration_is_seconds(tmp_path) -> None:
    path = tmp_path / "rec.ndjson"
    recorded = gadgetctl(
        "monitor",
        WAVEFORM,
        "--duration",
        "0.5",
        "--format",
        "table",
        "--interval",
        "10",
        "--record",
        path,
    )
    assert recorded.returncode == 0, recorded.stderr
    result = gadgetctl(
        "replay",
        path,
        "--loop",
        "--rate",
        "10000",
        "--duration",
        "1",
        "--format",
        "table",
        "--stats",
    )
    assert result.returncode == 0, result.stderr
    _frames, seconds, achieved, requested = frames_of(result)
    assert 1.0 <= seconds < 3.0  # wall-clock, not 10,000 frames
    # 10,000 Hz (the most --rate allows) is reached on a quiet fast machine (9,265 Hz was seen)
    # and not on a loaded one: the note is said at most once, and surely when far below.
    notes = result.stderr.count("not reached")
    assert notes <= 1
    if achieved < 0.8 * requested:
        assert notes == 1, result.stderr


def test_input_manager_run_duration_is_seconds() -> None:
    from gadgetctl.input import InputManager, ManagerOptions

    manager, configuration = InputManager.from_files(
        [WAVEFORM], options=ManagerOptions(entry_points=False)
    )
    with manager:
        manager.configure(configuration)
        started = time.monotonic()
        count = manager.run(rate=1_000_000, duration=0.5)
        elapsed = time.monotonic() - started
    assert 0.5 <= elapsed < 2.5 and count < 500_000


@pytest.fixture
def udp_port():
    """A loopback UDP port that takes (and ignores) what the DTrack emulator sends."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        yield str(sock.getsockname()[1])


@pytest.mark.parametrize("value", ["-1", "-0.5", "nan"])
@pytest.mark.parametrize("driver", ["DTrack_drv", "MotionStar_drv"])
def test_emulate_refuses_a_negative_duration(udp_port, driver: str, value: str) -> None:
    port = udp_port if driver == "DTrack_drv" else "0"
    result = gadgetctl("emulate", driver, "--port", port, "--duration", value, timeout=30)
    assert result.returncode == 2, (result.stdout, result.stderr)
    assert "--duration" in result.stderr and "Traceback" not in result.stderr


@pytest.mark.parametrize(
    "driver", ["DTrack_drv", "LinuxJoydev_drv", "PinchGlove_drv", "MotionStar_drv"]
)
def test_emulate_duration_is_seconds(tmp_path, udp_port, driver: str) -> None:
    where = {
        "DTrack_drv": ["--port", udp_port],
        "LinuxJoydev_drv": ["--path", str(tmp_path / "js0")],
        "PinchGlove_drv": ["--port", str(tmp_path / "pinch")],
        "MotionStar_drv": ["--port", "0"],
    }[driver]
    started = time.monotonic()
    result = gadgetctl("emulate", driver, *where, "--duration", "0.5", timeout=30)
    elapsed = time.monotonic() - started
    assert result.returncode == 0, result.stderr
    assert elapsed >= 0.5


@pytest.mark.parametrize(
    ("achieved", "said"),
    [
        (250.4, "about 250 frames per second"),
        (1.2, "about 1 frame per second"),
        (0.4, "about one frame every 2.5 seconds"),
    ],
)
def test_the_shortfall_note_says_the_pace_in_words_that_fit(achieved, said) -> None:
    """10,000 devices make less than a frame a second: the note said "about 0 frames"."""
    from types import SimpleNamespace

    from gadgetctl.cli.monitor_run import RateNotice

    told: list[str] = []
    notice = RateNotice(SimpleNamespace(rate_shortfall=(60.0, achieved)), tell=told.append)
    notice.check()
    notice.check()
    assert told == [
        f"the frame rate of 60 Hz is not reached: {said} (--duration counts seconds all the same)"
    ]
