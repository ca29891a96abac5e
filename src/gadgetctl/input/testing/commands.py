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


def reported(result: subprocess.CompletedProcess[str], code: str) -> list[str]:
    """The lines of a command's output that carry the diagnostic ``code``."""
    return [line for line in result.stdout.splitlines() if code in line]


def emulated_types(plugin: str) -> list[str]:
    """The element types ``gadgetctl emulate --list`` says the emulator of ``plugin`` serves."""
    listed = json.loads(run_gadgetctl("emulate", "--list", "--format", "json").stdout)
    return next(e for e in listed["emulators"] if e["plugin"] == plugin)["element_types"]


def doctor_finds_no_port(path: Path, plugin: str, port: str) -> subprocess.CompletedProcess[str]:
    """``gadgetctl doctor`` on a configuration whose serial ``port`` does not exist: exactly one
    DRV100 line, saying so, and the hint to start the plug-in's emulator. The result."""
    out = run_gadgetctl("doctor", str(path))
    problem = reported(out, "DRV100")
    assert len(problem) == 1 and f"{port} does not exist" in problem[0], out.stdout
    assert f"gadgetctl emulate {plugin}" in out.stdout
    return out


def validate_reports_units_beyond(config: str, tmp_path: Path, *expected: tuple[str, ...]) -> None:
    """``gadgetctl validate`` on ``config`` (its ``{port}`` /dev/null) fails with one CFG034
    line (a proxy reads a unit the device does not have) per ``expected``, in order, each
    holding every text of its tuple."""
    path = tmp_path / "t.jconf"
    path.write_text(config.format(port="/dev/null"))
    out = run_gadgetctl("validate", str(path))
    problems = reported(out, "CFG034")
    assert out.returncode == 1 and len(problems) == len(expected), out.stdout
    for line, texts in zip(problems, expected, strict=True):
        for text in texts:
            assert text in line, (text, line)


def emulated_and_serial_port_diagnosed(
    config: str, tmp_path: Path, plugin: str, element_types: list[str]
) -> None:
    """``gadgetctl emulate --list`` says the emulator of ``plugin`` serves ``element_types``, and
    ``gadgetctl doctor`` on ``config`` whose ``{port}`` does not exist says so and hints at that
    emulator (:func:`doctor_finds_no_port`)."""
    assert emulated_types(plugin) == element_types
    path = tmp_path / "t.jconf"
    path.write_text(config.format(port=tmp_path / "no-such-tty"))
    doctor_finds_no_port(path, plugin, "no-such-tty")
