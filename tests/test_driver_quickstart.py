"""The README's driver quick start, exactly as a new user runs it: `gadgetctl emulate DRIVER`
with its defaults in one terminal, `gadgetctl monitor drivers/DRIVER/example.jconf` in
another; samples of every kind the driver provides arrive through the example's proxies."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from conftest import REPO

# plug-in, the kinds its example configuration must deliver
DRIVERS = [
    ("LinuxJoydev_drv", {"digital", "analog"}),
    ("DTrack_drv", {"position", "digital", "analog"}),
    ("PinchGlove_drv", {"glove", "digital"}),
    ("MotionStar_drv", {"position"}),
    ("VRPN_drv", {"position", "digital", "analog"}),
]


def gadgetctl(*args: str, **kwargs) -> subprocess.Popen:
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "NO_COLOR": "1"}
    return subprocess.Popen([sys.executable, "-m", "gadgetctl", *args], cwd=REPO, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kwargs)


@pytest.mark.timeout(60)
@pytest.mark.parametrize(("driver", "kinds"), DRIVERS, ids=[d for d, _ in DRIVERS])
def test_emulate_then_monitor_the_example(driver, kinds):
    emulator = gadgetctl("emulate", driver)
    try:
        time.sleep(1.0)  # the emulator prints where it listens; give it a moment to be there
        assert emulator.poll() is None, emulator.communicate()[1]
        monitor = subprocess.run(
            [sys.executable, "-m", "gadgetctl", "monitor", f"drivers/{driver}/example.jconf",
             "--duration", "3", "--format", "ndjson"],
            cwd=REPO, capture_output=True, text=True, timeout=40)
    finally:
        emulator.send_signal(signal.SIGINT)
        out, err = emulator.communicate(timeout=15)
    assert emulator.returncode == 0 and "Traceback" not in err, err
    assert monitor.returncode == 0, monitor.stderr[-2000:]
    records = [json.loads(line) for line in monitor.stdout.splitlines() if line.strip()]
    seen = {r["kind"] for r in records if r.get("type") == "sample"}
    assert kinds <= seen, f"{driver}: got {sorted(seen)}; emulator said {out!r}"
