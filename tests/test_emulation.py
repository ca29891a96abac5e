"""The shared emulator scaffolding (`gadgetctl.emulation`) and what it gives every emulator:
clean-up on SIGTERM and SIGHUP as on Ctrl-C, endpoints that never take what is not theirs,
beacons that tell `doctor` a live emulator's path from a stale one (issue 12 item 4)."""

from __future__ import annotations

import argparse
import os
import signal
import socket
import stat
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from test_emulate import Emulation

from gadgetctl.emulation import Beacon, Fifo, PseudoTerminal, UnixSocket, duration_seconds, is_held

pytestmark = pytest.mark.timeout(60)

STOPS = [signal.SIGTERM, signal.SIGHUP, signal.SIGINT]


def stop_with(emulation: Emulation, signum: int) -> int:
    emulation.proc.send_signal(signum)
    code, err = emulation.finish(timeout=20)
    assert "Traceback" not in err, err
    return code


# -- every emulator cleans up, whatever stops it ------------------------------------------------


@pytest.mark.parametrize("signum", STOPS, ids=lambda s: signal.Signals(s).name)
def test_pinch_glove_emulator_removes_its_pty_link(tmp_path, signum) -> None:
    link = tmp_path / "gadgetctl-pinch"
    emulation = Emulation("emulate", "PinchGlove_drv", "--port", link)
    try:
        emulation.wait_for(r"<port>(.+)</port>")
        assert link.is_symlink() and is_held(link)
        target = os.readlink(link)
        assert stop_with(emulation, signum) == 0
        assert not os.path.lexists(link), f"{link} -> {target} left behind"
    finally:
        emulation.close()


@pytest.mark.parametrize("signum", STOPS, ids=lambda s: signal.Signals(s).name)
def test_joystick_emulator_removes_its_fifo(tmp_path, signum) -> None:
    fifo = tmp_path / "gadgetctl-js0"
    emulation = Emulation("emulate", "LinuxJoydev_drv", "--path", fifo)
    try:
        emulation.wait_for(r"<port_name>(.+)</port_name>")
        assert stat.S_ISFIFO(os.lstat(fifo).st_mode) and is_held(fifo)
        assert stop_with(emulation, signum) == 0
        assert not os.path.lexists(fifo)
    finally:
        emulation.close()


@pytest.mark.parametrize("driver", ["DTrack_drv", "MotionStar_drv"])
def test_network_emulators_end_cleanly_on_sigterm(driver) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sink:  # DTrack sends here
        sink.bind(("127.0.0.1", 0))
        emulation = Emulation("emulate", driver, "--port", str(sink.getsockname()[1]))
        try:
            emulation.wait_for(r"127\.0\.0\.1")
            assert stop_with(emulation, signal.SIGTERM) == 0
        finally:
            emulation.close()


SOCKET_EMULATOR = textwrap.dedent("""
    import sys
    from gadgetctl.emulation import UnixSocket, run

    class Emulator:
        def __init__(self, path):
            self.socket = UnixSocket(path)
        def start(self):
            self.socket.open()
        def stop(self):
            self.socket.close()

    sys.exit(run(Emulator(sys.argv[1]), announce=lambda: print("ready", flush=True)))
""")


@pytest.mark.parametrize("signum", STOPS, ids=lambda s: signal.Signals(s).name)
def test_a_unix_socket_made_through_run_is_removed_on_a_stop_signal(tmp_path, signum) -> None:
    path = tmp_path / "emu.sock"
    proc = subprocess.Popen(
        [sys.executable, "-c", SOCKET_EMULATOR, str(path)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout.readline() == "ready\n"
        assert stat.S_ISSOCK(os.lstat(path).st_mode) and is_held(path)
        proc.send_signal(signum)
        assert proc.wait(timeout=20) == 0, proc.stderr.read()
        assert not os.path.lexists(path)
    finally:
        proc.kill()
        proc.wait()


def test_sigkill_leaves_the_link_behind_and_doctor_knows_it_is_stale(tmp_path) -> None:
    """What no handler can catch: the link stays, nothing vouches for it any more."""
    link = tmp_path / "gadgetctl-pinch"
    emulation = Emulation("emulate", "PinchGlove_drv", "--port", link)
    try:
        emulation.wait_for(r"<port>(.+)</port>")
        emulation.proc.kill()
        emulation.proc.wait(timeout=20)
        assert link.is_symlink() and not is_held(link)
    finally:
        emulation.close()


# -- the endpoints ------------------------------------------------------------------------------


def test_pty_link_never_replaces_a_regular_file(tmp_path) -> None:
    precious = tmp_path / "notes"
    precious.write_text("mine")
    with pytest.raises(FileExistsError):
        PseudoTerminal(precious).open()
    assert precious.read_text() == "mine"


def test_pty_link_replaces_a_leftover_link_and_removes_only_its_own(tmp_path) -> None:
    link = tmp_path / "pinch"
    link.symlink_to("/dev/pts/nonexistent")  # a stale leftover
    pty = PseudoTerminal(link).open()
    assert os.readlink(link) == pty.address and is_held(link) and is_held(pty.address)
    link.unlink()
    link.symlink_to("/dev/null")  # somebody else's link meanwhile
    pty.close()
    assert os.readlink(link) == "/dev/null"
    assert pty.master < 0 and pty.write(b"x") == 0


def test_fifo_refuses_a_file_takes_over_a_fifo_and_removes_only_its_own(tmp_path) -> None:
    path = tmp_path / "js0"
    path.write_text("data")
    with pytest.raises(FileExistsError):
        Fifo(path).create()
    assert path.read_text() == "data"
    path.unlink()
    os.mkfifo(path)
    fifo = Fifo(path).create()  # a leftover FIFO is taken over
    assert is_held(path)
    fifo.replace()  # unplugged and plugged in: a new inode, still vouched for
    assert stat.S_ISFIFO(os.lstat(path).st_mode) and is_held(path)
    fifo.remove()
    assert not os.path.lexists(path)
    os.mkfifo(path)  # made by another emulator after us
    fifo.remove()
    assert stat.S_ISFIFO(os.lstat(path).st_mode)


def test_unix_socket_refuses_a_file(tmp_path) -> None:
    path = tmp_path / "sock"
    path.write_text("x")
    with pytest.raises(FileExistsError):
        UnixSocket(path).open()
    assert path.read_text() == "x"


def test_beacon_vouches_only_while_open(tmp_path) -> None:
    path = tmp_path / "js0"
    os.mkfifo(path)
    beacon = Beacon(path)
    assert beacon.held and is_held(path)
    assert not Beacon(path).held  # one vouches; a second one is not needed
    beacon.close()
    assert not is_held(path)
    assert is_held(tmp_path / "missing") is False


@pytest.mark.parametrize("text", ["-1", "-0.001", "nan", "inf", "soon"])
def test_duration_must_be_finite_seconds(text) -> None:
    with pytest.raises(argparse.ArgumentTypeError):
        duration_seconds(text)
    assert duration_seconds("0") == 0.0 and duration_seconds("2.5") == 2.5


def test_emulation_imports_nothing_else_from_gadgetctl() -> None:
    import ast

    package = Path(__file__).resolve().parents[1] / "src" / "gadgetctl" / "emulation"
    for path in package.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = (
                [a.name for a in node.names]
                if isinstance(node, ast.Import)
                else (
                    [node.module or ""]
                    if isinstance(node, ast.ImportFrom) and not node.level
                    else []
                )
            )
            for name in names:
                assert not name.startswith("gadgetctl.") or name.startswith(
                    "gadgetctl.emulation"
                ), f"{path.name} imports {name}"
