"""The command line run on test configurations: ``python -m gadgetctl`` in a child process
(:func:`run_gadgetctl`), and ``monitor --format ndjson`` read back (:func:`monitor_ndjson`,
:func:`samples_of`)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path

from gadgetctl.input.testing.configs import checkout


def run_gadgetctl(
    *args: str,
    timeout: float = 50,
    cwd: Path | None = None,
    env: Mapping[str, str] | None = None,
) -> subprocess.CompletedProcess[str]:
    """``python -m gadgetctl ARGS`` in a child process (in the checkout unless ``cwd``; ``env``
    added to this process's environment), its output captured as text."""
    return subprocess.run(
        [sys.executable, "-m", "gadgetctl", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=cwd or checkout(),
        env=None if env is None else {**os.environ, **env},
    )


def monitor_ndjson(
    config: Path,
    *args: str,
    duration: float = 1,
    timeout: float = 30,
    env: Mapping[str, str] | None = None,
) -> tuple[subprocess.CompletedProcess[str], list[dict]]:
    """``gadgetctl monitor CONFIG ARGS --duration D --format ndjson`` in a child process: its
    result and the records it printed (every line must be one JSON record)."""
    done = run_gadgetctl(
        "monitor", str(config), *args, "--duration", f"{duration:g}", "--format", "ndjson",
        timeout=timeout, env=env,
    )  # fmt: skip
    return done, [json.loads(line) for line in done.stdout.splitlines() if line.strip()]


def samples_of(records: list[dict], device: str | None = None) -> list[dict]:
    """The sample records (of ``device``, if named) among monitor records."""
    return [
        r
        for r in records
        if r.get("type") == "sample" and (device is None or r.get("device") == device)
    ]
