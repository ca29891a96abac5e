"""A command run in a detached tmux pane of a given size, read back with capture-pane: the
live view as a user's terminal shows it (after every redraw, resize and cursor movement).

Each pane has its own tmux server (``-L`` with a unique socket name), killed on close.
Tests wait for screen contents with :meth:`Pane.wait_for` (polling with a deadline), never
for a fixed time.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import time
import uuid
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def require_tmux() -> str:
    tmux = shutil.which("tmux")
    if tmux is None and os.environ.get("CI"):
        raise AssertionError("tmux is missing: .ci/run installs it")
    if tmux is None:
        pytest.skip("tmux is not installed")
    return tmux


class Pane:
    def __init__(self, command: str, *, cols: int = 120, rows: int = 40) -> None:
        self.tmux = require_tmux()
        self.socket = f"gadgetctl-test-{uuid.uuid4().hex[:12]}"
        env = {**os.environ, "NO_COLOR": "1"}
        env.pop("GADGETCTL_DEBUG", None)
        env.pop("TMUX", None)
        self._env = env
        self._run(
            "-f",
            "/dev/null",
            "new-session",
            "-d",
            "-s",
            "t",
            "-x",
            str(cols),
            "-y",
            str(rows),
            "-c",
            str(REPO),
            f"{command}; echo EXIT=$?; sleep 60",
        )

    def _run(self, *args: str) -> str:
        done = subprocess.run(
            [self.tmux, "-L", self.socket, *args],
            env=self._env,
            capture_output=True,
            text=True,
            timeout=20,
            check=True,
        )
        return done.stdout

    def screen(self) -> str:
        return self._run("capture-pane", "-p", "-t", "t")

    def wait_for(self, pattern: str, timeout: float = 20.0) -> re.Match:
        """The first match of ``pattern`` (multiline) on the screen; fails after ``timeout``."""
        deadline = time.monotonic() + timeout
        regex = re.compile(pattern, re.MULTILINE)
        while True:
            text = self.screen()
            found = regex.search(text)
            if found:
                return found
            if time.monotonic() > deadline:
                raise AssertionError(f"{pattern!r} never appeared; the screen:\n{text}")
            time.sleep(0.05)

    def line(self, pattern: str, timeout: float = 20.0) -> str:
        """The whole screen line where ``pattern`` first matches."""
        found = self.wait_for(f"^.*(?:{pattern}).*$", timeout)
        return found.group(0)

    def keys(self, *keys: str, literal: bool = False) -> None:
        self._run("send-keys", "-t", "t", *(("-l",) if literal else ()), *keys)

    def resize(self, cols: int, rows: int) -> None:
        self._run("resize-window", "-t", "t", "-x", str(cols), "-y", str(rows))

    def close(self) -> None:
        subprocess.run(
            [self.tmux, "-L", self.socket, "kill-server"], capture_output=True, timeout=20
        )

    def __enter__(self) -> Pane:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
