"""Stale emulator endpoints: a pty link or FIFO that no live emulator or program holds.

An emulator killed without clean-up leaves its symlink to a pseudo-terminal or its FIFO
behind. The FIFO then has no writer, and the pts number is soon reused by somebody's
terminal: a driver opening the link would write its handshake into that terminal. A live
gadgetctl emulator vouches for every path it made (:mod:`gadgetctl.emulation.beacon`);
without that, Linux's /proc tells who holds a pty's master side (``tty-index`` in the
fdinfo of a ``/dev/ptmx`` descriptor), whose controlling terminal a pts is (``tty_nr`` of
``/proc/PID/stat``) and who has a FIFO open for writing. Processes of other users cannot be
looked into without privileges; what cannot be seen is not claimed.
"""

from __future__ import annotations

import contextlib
import os
import stat
from dataclasses import dataclass
from pathlib import Path

from gadgetctl.emulation.beacon import is_held

PROC = Path("/proc")
PTS_DIR = "/dev/pts/"


@dataclass(frozen=True, slots=True)
class Holder:
    pid: int
    command: str

    def __str__(self) -> str:
        return f"{self.command} (pid {self.pid})"


@dataclass(frozen=True, slots=True)
class Staleness:
    """Why a path looks stale: ``severe`` when data would go somewhere harmful."""

    detail: str
    hint: str
    severe: bool = True


def _processes(proc: Path) -> list[Path]:
    try:
        return [p for p in proc.iterdir() if p.name.isdigit()]
    except OSError:
        return []


def _command(pid_dir: Path) -> str:
    with contextlib.suppress(OSError):
        words = [
            w.decode(errors="replace") for w in (pid_dir / "cmdline").read_bytes().split(b"\0") if w
        ]
        if words:
            text = " ".join(" ".join([os.path.basename(words[0]), *words[1:]]).split())
            return text if len(text) <= 120 else text[:117] + "..."
    with contextlib.suppress(OSError):
        return (pid_dir / "comm").read_text().strip()
    return "?"


def terminal_of(rdev: int, proc: Path = PROC) -> Holder | None:
    """A process whose controlling terminal is the tty with device number ``rdev``."""
    for pid_dir in _processes(proc):
        with contextlib.suppress(OSError, ValueError, IndexError):
            text = (pid_dir / "stat").read_text()
            fields = text[text.rindex(")") + 2 :].split()
            if int(fields[4]) == rdev:  # state, ppid, pgrp, session, tty_nr
                return Holder(int(pid_dir.name), _command(pid_dir))
    return None


def pty_master_holder(index: int, proc: Path = PROC) -> Holder | None:
    """A process holding the master side of /dev/pts/``index`` (as far as this user can see)."""
    for pid_dir in _processes(proc):
        fd_dir = pid_dir / "fd"
        try:
            fds = list(fd_dir.iterdir())
        except OSError:
            continue
        for fd in fds:
            with contextlib.suppress(OSError):
                if not os.readlink(fd).endswith("ptmx"):
                    continue
                info = (pid_dir / "fdinfo" / fd.name).read_text()
                for line in info.splitlines():
                    if line.startswith("tty-index:") and int(line.split()[1]) == index:
                        return Holder(int(pid_dir.name), _command(pid_dir))
    return None


def fifo_writer(path: str, proc: Path = PROC) -> Holder | None:
    """A process holding the FIFO at ``path`` open for writing (as far as this user can see)."""
    try:
        target = os.stat(path)
    except OSError:
        return None
    for pid_dir in _processes(proc):
        fd_dir = pid_dir / "fd"
        try:
            fds = list(fd_dir.iterdir())
        except OSError:
            continue
        for fd in fds:
            with contextlib.suppress(OSError, ValueError):
                st = os.stat(fd)
                if (st.st_dev, st.st_ino) != (target.st_dev, target.st_ino):
                    continue
                flags = next(
                    line
                    for line in (pid_dir / "fdinfo" / fd.name).read_text().splitlines()
                    if line.startswith("flags:")
                )
                if int(flags.split()[1], 8) & os.O_ACCMODE in (os.O_WRONLY, os.O_RDWR):
                    return Holder(int(pid_dir.name), _command(pid_dir))
    return None


def staleness(path: str, proc: Path = PROC) -> Staleness | None:
    """Why the pty link or FIFO at ``path`` looks stale, or None when it is held (or is
    neither a pty nor a FIFO, or cannot be told)."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    real = os.path.realpath(path)
    is_pts = (
        stat.S_ISCHR(st.st_mode) and real.startswith(PTS_DIR) and real[len(PTS_DIR) :].isdigit()
    )
    is_fifo = stat.S_ISFIFO(st.st_mode)
    if not (is_pts or is_fifo):
        return None
    if is_held(path) or (os.path.islink(path) and is_held(real)):
        return None
    if is_fifo:
        writer = fifo_writer(path, proc)
        if writer is not None:
            return None
        return Staleness(
            "is a FIFO that no emulator or program writes: a driver would wait for data forever",
            "a stale FIFO left by an emulator that was killed? remove it and start the emulator "
            "again (`gadgetctl emulate DRIVER`)",
        )
    link = f"a link to {real}" if os.path.islink(path) else "a pseudo-terminal"
    terminal = terminal_of(st.st_rdev, proc)
    if terminal is not None:
        return Staleness(
            f"is {link} that no emulator holds: it is the terminal of {terminal}; a driver "
            "would write into that terminal",
            "a stale link left by an emulator that was killed: remove it and start the emulator "
            "again (`gadgetctl emulate DRIVER`)",
        )
    holder = pty_master_holder(int(real[len(PTS_DIR) :]), proc)
    if holder is not None:
        return Staleness(
            f"is {link} held by {holder}, not by a gadgetctl emulator",
            "make sure that program stands in for the device",
            severe=False,
        )
    return Staleness(
        f"is {link} that no emulator holds",
        "a stale link left by an emulator that was killed: remove it and start the "
        "emulator again (`gadgetctl emulate DRIVER`)",
    )
