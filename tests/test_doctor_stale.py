"""`gadgetctl doctor` flags a pty link or FIFO that no emulator or program holds (DRV108)
instead of calling it fine: the leftovers of an emulator killed without clean-up."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from test_doctor import config, doctor_json, joydev, port_codes

from gadgetctl.doctor.model import Status
from gadgetctl.doctor.ports import check_path
from gadgetctl.emulation import Fifo, PseudoTerminal

pytestmark = pytest.mark.timeout(60)

HOLD_AS_TERMINAL = (
    "import os, sys\n"
    "os.setsid()\n"
    "fd = os.open(sys.argv[1], os.O_RDWR)  # a session leader opening a tty: its controlling terminal\n"
    "print('ready', flush=True)\n"
    "sys.stdin.read()\n"
)


def pinch(port: Path | str) -> str:
    return f'<pinch_glove name="Glove" version="1"><port>{port}</port></pinch_glove>'


def test_a_fifo_that_nobody_writes_is_stale(cli, tmp_path) -> None:
    fifo = tmp_path / "gadgetctl-js0"
    os.mkfifo(fifo)  # what a killed emulator leaves
    code, report = doctor_json(cli, config(tmp_path, joydev(fifo), drivers=("LinuxJoydev_drv",)))
    [check] = [c for d in report["devices"] for c in d["checks"]]
    assert check["code"] == "DRV108" and check["status"] == "problem", check
    assert "no emulator or program writes" in check["detail"] and "stale" in check["hint"]
    assert "DRV108" in port_codes(report) and code == 1


def test_a_fifo_a_program_writes_or_an_emulator_holds_is_fine(tmp_path) -> None:
    fed = tmp_path / "fed"
    os.mkfifo(fed)
    writer = os.open(fed, os.O_RDWR)  # some program holding it for writing
    try:
        assert check_path(str(fed), "file").status is Status.OK
    finally:
        os.close(writer)
    held = Fifo(tmp_path / "held").create()  # an emulator waiting for its reader
    try:
        result = check_path(str(held.path), "file")
        assert result.status is Status.OK and "held by a live emulator" in result.detail
    finally:
        held.remove()


def test_a_pty_link_now_pointing_at_somebodys_terminal_is_stale(cli, tmp_path) -> None:
    """The issue's case: the emulator was killed, its pts number went to a terminal."""
    master, slave = os.openpty()
    terminal = subprocess.Popen(
        [sys.executable, "-c", HOLD_AS_TERMINAL, os.ttyname(slave)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert terminal.stdout.readline() == "ready\n"
        link = tmp_path / "gadgetctl-pinch"
        link.symlink_to(os.ttyname(slave))
        code, report = doctor_json(cli, config(tmp_path, pinch(link), drivers=("PinchGlove_drv",)))
        [check] = [c for d in report["devices"] for c in d["checks"]]
        assert check["code"] == "DRV108" and check["status"] == "problem", check
        assert (
            "the terminal of python" in check["detail"] and f"pid {terminal.pid}" in check["detail"]
        )
        assert "would write into that terminal" in check["detail"]
        assert code == 1
    finally:
        terminal.stdin.close()
        terminal.wait(timeout=10)
        os.close(master)
        os.close(slave)


def test_a_pty_held_by_another_program_is_a_warning_naming_it(tmp_path) -> None:
    master, slave = os.openpty()  # held by this test process, not by an emulator
    try:
        link = tmp_path / "bridge"
        link.symlink_to(os.ttyname(slave))
        result = check_path(str(link), "serial")
        assert result.status is Status.WARNING and result.code == "DRV108"
        assert f"(pid {os.getpid()}), not by a gadgetctl emulator" in result.detail
    finally:
        os.close(master)
        os.close(slave)


def test_a_live_emulators_pty_link_is_fine(tmp_path) -> None:
    pty = PseudoTerminal(tmp_path / "gadgetctl-pinch").open()
    try:
        result = check_path(str(pty.link), "serial")
        assert result.status is Status.OK and "held by a live emulator" in result.detail
        assert check_path(pty.address, "serial").status is Status.OK
    finally:
        pty.close()


def test_a_link_to_a_vanished_pts_says_it_is_stale(tmp_path) -> None:
    link = tmp_path / "gadgetctl-pinch"
    link.symlink_to("/dev/pts/4000000")  # beyond kernel.pty.max: certainly gone
    result = check_path(str(link), "serial")
    assert result.code == "DRV100" and "stale link left by an emulator" in result.hint
