"""Emulators that meet something in their way (issue 25 item 11): a second emulator refuses the
link a running one holds, naming it; a taken TCP port is named; `emulate --list` gives whole
sentences; a plug-in whose Python module is missing says what to install in one line, and
`drivers list` shows it as not loadable."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time

import pytest

from conftest import REPO

pytestmark = pytest.mark.timeout(60)

BLOCKER = """import sys
class Blocker:
    @staticmethod
    def find_spec(name, path=None, target=None):
        if name.split(".")[0] in ("pythonosc", "sdl2"):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None
sys.meta_path.insert(0, Blocker())
sys.argv = ["gadgetctl", *sys.argv[1:]]
from gadgetctl.cli.main import run
run()
"""


def gadgetctl(*args: object, timeout: float = 30, script: list[str] | None = None):
    return subprocess.run(
        [sys.executable, *(script or ["-m", "gadgetctl"]), *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=REPO,
    )


def test_a_second_emulator_refuses_the_link_of_a_running_one(tmp_path):
    link = tmp_path / "pinch"
    first = subprocess.Popen(
        [sys.executable, "-m", "gadgetctl", "emulate", "PinchGlove_drv", "--port", str(link)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=REPO,
    )
    try:
        deadline = time.monotonic() + 20
        while not link.is_symlink():
            assert first.poll() is None and time.monotonic() < deadline, "no link appeared"
            time.sleep(0.02)
        target = os.readlink(link)
        second = gadgetctl("emulate", "PinchGlove_drv", "--port", link, "--duration", "5")
        assert second.returncode == 2
        assert second.stderr.splitlines() == [
            f"gadgetctl: error: emulate PinchGlove_drv: {link}: is the link of another emulator "
            "that is running; stop it or give this one another --port"
        ]
        assert os.readlink(link) == target  # still the first emulator's pty
    finally:
        first.terminate()
        first.wait(timeout=20)
    assert not link.exists()  # the first one removed its own link


def test_a_taken_tcp_port_is_named():
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        result = gadgetctl("emulate", "MotionStar_drv", "--port", port, "--duration", "1")
    assert result.returncode == 2
    assert result.stderr.splitlines() == [
        f"gadgetctl: error: emulate MotionStar_drv: cannot bind TCP port {port} on 127.0.0.1: "
        "Address already in use"
    ]


def test_the_list_gives_whole_sentences(cli):
    result = cli("emulate", "--list")
    summaries = [line.strip() for line in result.stdout.splitlines() if line.startswith("    ")]
    assert len(summaries) >= 19
    for summary in summaries:
        assert summary.endswith("."), summary
        assert "`" not in summary and ":mod:" not in summary, summary


def test_a_missing_module_says_what_to_install(tmp_path):
    script = tmp_path / "without_sdl.py"
    script.write_text(BLOCKER, encoding="utf-8")
    result = gadgetctl("emulate", "SdlJoystick_drv", "--duration", "1", script=[str(script)])
    assert result.returncode == 2
    assert result.stderr.splitlines() == [
        "gadgetctl: error: emulate SdlJoystick_drv: needs the Python module sdl2: "
        "pip install PySDL2 pysdl2-dll (or gadgetctl[sdl])"
    ]
    listed = gadgetctl("drivers", "list", script=[str(script)]).stdout.splitlines()

    def block_of(name: str) -> list[str]:
        start = next(i for i, line in enumerate(listed) if line.startswith(f"{name} "))
        block = []
        for line in listed[start + 1 :]:
            if not line.startswith("    "):
                break
            block.append(line)
        return block

    assert any(
        "! not loadable: needs the Python module sdl2" in line
        for line in block_of("SdlJoystick_drv")
    )
    # TUIO_drv decodes OSC itself: without python-osc it still loads
    assert not any("not loadable" in line for line in block_of("TUIO_drv"))
