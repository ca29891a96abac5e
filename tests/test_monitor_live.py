"""The live view of `gadgetctl monitor` under a pseudo-terminal (pexpect): it draws, reacts
to p and q, forwards keys to simulated devices, shows faults, and always gives the
terminal back in the mode it found it (compared with `stty -g`).

NO_COLOR is set, so the screen carries text and cursor movements only and the patterns
below match the drawn lines directly.
"""

from __future__ import annotations

import os
import re
import shlex
import signal
import sys
import time
from pathlib import Path

import pytest

from conftest import REPO

pexpect = pytest.importorskip("pexpect")

pytestmark = pytest.mark.timeout(90)

WAVEFORM = REPO / "examples" / "waveform.jconf"
ALL_DEVICES = REPO / "examples" / "all_devices.jconf"
STTY = re.compile(r"STTY=([0-9a-f:]+)")


def shell(command: str, *, rows: int = 45, cols: int = 200) -> pexpect.spawn:
    """``command`` run by bash in a fresh pseudo-terminal, between two `stty -g`."""
    env = {**os.environ, "NO_COLOR": "1", "TERM": "xterm-256color"}
    env.pop("GADGETCTL_DEBUG", None)
    script = f'echo "STTY=$(stty -g)"; {command}; echo "EXIT=$?"; echo "STTY=$(stty -g)"'
    return pexpect.spawn(
        "bash",
        ["--norc", "--noprofile", "-c", script],
        cwd=str(REPO),
        env=env,
        dimensions=(rows, cols),
        encoding="utf-8",
        timeout=20,
        # a signal can end a frame's write inside a multi-byte character (the
        # terminal shows one odd glyph); what these tests judge is the text
        # around it, so a cut character must not raise UnicodeDecodeError
        codec_errors="replace",
    )


def monitor_command(*args: str | Path) -> str:
    return " ".join(
        shlex.quote(str(a)) for a in (sys.executable, "-m", "gadgetctl", "monitor", *args)
    )


def stty_before(child: pexpect.spawn) -> str:
    child.expect(STTY)
    return child.match.group(1)


def finish(child: pexpect.spawn) -> tuple[int, str]:
    """Exit status of the monitor and `stty -g` after it."""
    child.expect(r"EXIT=(\d+)")
    code = int(child.match.group(1))
    child.expect(STTY)
    after = child.match.group(1)
    child.expect(pexpect.EOF)
    return code, after


def monitor_pid(shell_pid: int, timeout: float = 10) -> int:
    """The process bash started for the monitor (its only child)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        children = []
        for task in Path(f"/proc/{shell_pid}/task").glob("*/children"):
            children += [int(p) for p in task.read_text().split()]
        if children:
            return children[0]
        time.sleep(0.05)
    raise AssertionError("the monitor did not start")


def test_live_view_draws_pauses_quits_and_restores_the_terminal():
    child = shell(monitor_command(WAVEFORM))
    try:
        before = stty_before(child)
        child.expect(r"Waveform Noise\s+waveform_device\s+running\s+\d")
        child.expect(r"VJNoise\s+alias → Noise Proxy\s+active")
        child.expect(r"q quit  p pause")
        child.send("p")
        child.expect("PAUSED")
        child.send("p")
        child.expect(r"fps  [\d.]+ s\x1b\[K")  # the header without PAUSED
        child.send("q")
        code, after = finish(child)
    finally:
        child.close(force=True)
    assert code == 0
    assert after == before


def test_keys_are_forwarded_to_the_keyboard_mouse_device_and_drive_simulated_devices():
    child = shell(
        monitor_command(ALL_DEVICES, "Sim Buttons", "Sim Head", "Button 0 Proxy", "--no-mouse")
    )
    try:
        before = stty_before(child)
        child.expect(r"other keys and the mouse → Sim Keyboard")
        child.expect(r"digital\s+0:○\s+1:○")
        child.send(" ")  # KEY_SPACE: button 0 of Sim Buttons
        child.expect(r"digital\s+0:[●○][ ↕]\u00d71")
        child.expect(
            r"Button 0 Proxy\s+digital_proxy → Sim Buttons\[0\]\s+active\s+[●○][ ↑↓]\u00d71"
        )
        child.send("\x1b[A")  # Up arrow: KEY_UP, forward 5 cm
        child.expect(r"position 0\s+x \+0\.000 y \+1\.800 z -0\.050 m")
        child.send("\r")  # KEY_RETURN: button 1
        child.expect(r"1:[●○][ ↕]\u00d71")
        child.send("\x03")  # Ctrl-C quits too (the terminal delivers it as a key)
        code, after = finish(child)
    finally:
        child.close(force=True)
    assert code == 0
    assert after == before


def test_marker_prompt_writes_a_named_marker(tmp_path):
    path = tmp_path / "marked.ndjson"
    child = shell(monitor_command(WAVEFORM, "Waveform Noise", "--record", path))
    try:
        before = stty_before(child)
        child.expect(r"Waveform Noise\s+waveform_device\s+running")
        child.send("m")
        child.expect("marker name")
        child.send("button test\r")
        child.expect("marker 'button test' written to the recording")
        child.send("q")
        code, after = finish(child)
    finally:
        child.close(force=True)
    assert (code, after) == (0, before)
    lines = path.read_text().splitlines()
    assert any('"type":"marker","name":"button test"' in line for line in lines)
    assert (
        '"type":"end"' in lines[-1]
        and '"reason":"closed"' in lines[-1]
        and '"markers":1' in lines[-1]
    )


def test_a_faulted_device_shows_in_the_live_view_while_the_others_keep_their_rate(tmp_path):
    from test_monitor_cli import faulty_configuration

    config = faulty_configuration(tmp_path)
    child = shell(monitor_command(config))
    try:
        before = stty_before(child)
        child.expect(r"Bad Sensor\s+faulty_device\s+faulted .*device unplugged", timeout=20)
        child.expect(r"Bad Proxy\s+analog_proxy → Bad Sensor\[0\]\s+active")
        # Wait until the view shows the good device at its configured rate: the screen
        # redraws several times a second, and the first frames come before the rate window
        # has filled (and, on a loaded machine, while sampling catches up). A faulted device
        # slowing the others would keep the rate below 500 Hz until the deadline.
        rate, deadline = 0.0, time.monotonic() + 30
        while rate != pytest.approx(500.0, rel=0.03) and time.monotonic() < deadline:
            child.expect(r"Good Wave\s+waveform_device\s+running\s+(\d+\.\d) Hz")
            rate = float(child.match.group(1))
        child.send("q")
        code, after = finish(child)
    finally:
        child.close(force=True)
    assert rate == pytest.approx(500.0, rel=0.03)
    assert code == 1  # a device faulted
    assert after == before


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_ends_the_live_view_and_restores_the_terminal(tmp_path, signum):
    path = tmp_path / "signalled.ndjson"
    child = shell(monitor_command(WAVEFORM, "--record", path))
    try:
        before = stty_before(child)
        child.expect(r"Waveform Noise\s+waveform_device\s+running")
        os.kill(monitor_pid(child.pid), signum)
        code, after = finish(child)
    finally:
        child.close(force=True)
    assert code in (0, 1)
    assert after == before
    reason = "terminated" if signum == signal.SIGTERM else "interrupted"
    last = path.read_text().splitlines()[-1]
    assert '"type":"end"' in last and f'"reason":"{reason}"' in last


def test_the_demo_uses_the_live_view_on_a_terminal():
    child = shell(
        " ".join(
            shlex.quote(str(a))
            for a in (sys.executable, "-m", "gadgetctl", "demo", "--duration", "1.5")
        )
    )
    try:
        before = stty_before(child)
        child.expect(r"gadgetctl demo .*waveform\.jconf")
        child.expect(r"Waveform Sticks\s+waveform_device\s+running")
        code, after = finish(child)
    finally:
        child.close(force=True)
    assert (code, after) == (0, before)


def test_a_replay_in_the_live_view_stays_on_screen_when_it_ends(tmp_path):
    import subprocess

    path = tmp_path / "short.ndjson"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "gadgetctl",
            "monitor",
            str(WAVEFORM),
            "--duration",
            "1",
            "--format",
            "ndjson",
            "--record",
            str(path),
        ],
        cwd=REPO,
        check=True,
        capture_output=True,
        timeout=60,
    )
    command = " ".join(
        shlex.quote(str(a))
        for a in (sys.executable, "-m", "gadgetctl", "replay", path, "--speed", "4")
    )
    child = shell(command)
    try:
        before = stty_before(child)
        child.expect(r"gadgetctl replay .*at x4")
        child.expect(r"Waveform Noise\s+waveform_device\s+running")
        child.expect(r"FINISHED \(q quits\)")
        child.send("q")
        code, after = finish(child)
    finally:
        child.close(force=True)
    assert (code, after) == (0, before)
