"""A `gadgetctl serve` process for tests: started on an OS-chosen loopback port (or inside a
network namespace), its JSON event lines collected by a thread, stopped by a signal."""

from __future__ import annotations

import json
import os
import queue
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from conftest import REPO


class ServeProcess:
    def __init__(
        self, *args: str | Path, prefix: list[str] | None = None, timeout: float = 30.0
    ) -> None:
        env = {**os.environ, "PYTHONUNBUFFERED": "1", "NO_COLOR": "1"}
        command = [
            *(prefix or []),
            sys.executable,
            "-m",
            "gadgetctl",
            "serve",
            *map(str, args),
            "--format",
            "json",
        ]
        if "--port" not in args:
            command += ["--port", "0"]
        self.process = subprocess.Popen(
            command, cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        self.events: list[dict] = []
        self._lines: queue.Queue[dict | None] = queue.Queue()
        self._errors: list[str] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        self._error_reader = threading.Thread(
            target=lambda: self._errors.extend(self.process.stderr), daemon=True
        )
        self._error_reader.start()
        first = self.next_event(timeout)
        if first is None or first.get("event") != "listening":
            self.process.kill()
            raise AssertionError(
                f"serve did not start: {first} {self.process.communicate()[1][-3000:]}"
            )
        self.port: int = first["port"]
        self.listening = first

    def _read(self) -> None:
        for line in self.process.stdout:
            try:
                record = json.loads(line)
            except ValueError:
                record = {"event": "text", "text": line}
            self.events.append(record)
            self._lines.put(record)
        self._lines.put(None)

    def next_event(self, timeout: float = 10.0) -> dict | None:
        try:
            return self._lines.get(timeout=timeout)
        except queue.Empty:
            return None

    def wait_event(self, kind: str, timeout: float = 10.0) -> dict:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            event = self.next_event(max(0.01, deadline - time.monotonic()))
            if event is None and self.process.poll() is not None:
                break
            if event is not None and event.get("event") == kind:
                return event
        raise AssertionError(f"no {kind!r} event within {timeout} s; events: {self.events[-5:]}")

    def alive(self) -> bool:
        return self.process.poll() is None

    @property
    def stderr(self) -> str:
        return "".join(self._errors)

    def _finish(self, timeout: float) -> None:
        """Wait for the readers (the only ones reading the pipes) to reach the end."""
        self.process.wait(timeout)
        self._reader.join(timeout)
        self._error_reader.join(timeout)

    def stop(self, sig: int = signal.SIGTERM, timeout: float = 20.0) -> int:
        if self.process.poll() is None:
            self.process.send_signal(sig)
        try:
            self._finish(timeout)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self._finish(10)
            raise AssertionError(
                f"serve did not stop within {timeout} s after signal {sig}"
            ) from None
        return self.process.returncode

    def kill(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
        self._finish(10)

    def __enter__(self) -> ServeProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        if self.process.poll() is None:
            self.kill()
