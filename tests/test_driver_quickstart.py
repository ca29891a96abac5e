"""The README's driver quick start, exactly as a new user runs it: `gadgetctl emulate DRIVER`
with its defaults in one terminal, `gadgetctl monitor drivers/DRIVER/example.jconf` in
another; samples of every kind the driver provides arrive through the example's proxies."""

from __future__ import annotations

import json
import os
import re
import selectors
import signal
import subprocess
import sys
import time

import pytest

from gadgetctl.input.testing.configs import fixed_addresses

from conftest import REPO

# plug-in, the kinds its example configuration must deliver, what the emulator prints once
# it is where the example configuration looks
DRIVERS = [
    ("LinuxJoydev_drv", {"digital", "analog"}, r"<port_name>"),
    ("DTrack_drv", {"position", "digital", "analog"}, r"<receive_port>"),
    ("ElexolEther24_drv", {"digital"}, r"<ip_address>"),
    ("TUIO_drv", {"digital", "analog"}, r"<port>"),
    ("OptiTrack_drv", {"position"}, r"<port>"),
    ("PinchGlove_drv", {"glove", "digital"}, r"<port>"),
    ("MotionStar_drv", {"position"}, r"<server_port>"),
    ("VRPN_drv", {"position", "digital", "analog"}, r"VRPN devices? on"),
    ("IS900_drv", {"position", "digital", "analog"}, r"<port>"),
    ("SpaceBall_drv", {"digital", "analog"}, r"<port>"),
    ("Fastrak_drv", {"position", "digital"}, r"<port>"),
    ("DataGlove_drv", {"analog", "glove"}, r"<port>"),
    ("SerialEncoder_drv", {"position"}, r"<port>"),
    ("ThreeDMouse_drv", {"position", "digital"}, r"<port>"),
    ("Flock_drv", {"position"}, r"<port>"),
    ("DataGloveUltraWireless_drv", {"analog", "command"}, r"<port>"),
    ("IBox_drv", {"digital", "analog"}, r"<port>"),
    ("Trackd_drv", {"position", "digital", "analog"}, r"Press Ctrl-C"),
    ("Wanda_drv", {"digital", "analog"}, r"<port>"),
]
# The examples use fixed addresses (/tmp/gadgetctl-pinch, TCP 6000, ...): two test runs on
# one machine would take them from each other, so runs take turns (fixed_addresses).


def wait_for_output(proc: subprocess.Popen, pattern: str, timeout: float = 30.0) -> str:
    """Read the emulator's stdout until ``pattern`` appears (it then is where it says)."""
    regex, text = re.compile(pattern), ""
    deadline = time.monotonic() + timeout
    with selectors.DefaultSelector() as selector:
        selector.register(proc.stdout, selectors.EVENT_READ)
        while not regex.search(text):
            left = deadline - time.monotonic()
            assert left > 0, f"no {pattern!r} within {timeout} s: {text!r}"
            if selector.select(left):
                chunk = os.read(proc.stdout.fileno(), 4096)
                assert chunk, f"the emulator ended: {text!r}"
                text += chunk.decode()
    return text


def gadgetctl(*args: str, **kwargs) -> subprocess.Popen:
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "NO_COLOR": "1"}
    return subprocess.Popen(
        [sys.executable, "-m", "gadgetctl", *args],
        cwd=REPO,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kwargs,
    )


@pytest.mark.timeout(120)
@pytest.mark.parametrize(("driver", "kinds", "ready"), DRIVERS, ids=[d for d, _, _ in DRIVERS])
def test_emulate_then_monitor_the_example(driver, kinds, ready):
    with fixed_addresses():
        emulator = gadgetctl("emulate", driver)
        try:
            said = wait_for_output(emulator, ready)
            monitor = subprocess.run(
                [
                    sys.executable,
                    "-m",
                    "gadgetctl",
                    "monitor",
                    f"drivers/{driver}/example.jconf",
                    "--duration",
                    "3",
                    "--format",
                    "ndjson",
                ],
                cwd=REPO,
                capture_output=True,
                text=True,
                timeout=40,
            )
        finally:
            emulator.send_signal(signal.SIGINT)
            out, err = emulator.communicate(timeout=15)
    assert emulator.returncode == 0 and "Traceback" not in err, err
    assert monitor.returncode == 0, monitor.stderr[-2000:]
    records = [json.loads(line) for line in monitor.stdout.splitlines() if line.strip()]
    seen = {r["kind"] for r in records if r.get("type") == "sample"}
    assert kinds <= seen, f"{driver}: got {sorted(seen)}; emulator said {said + out!r}"
