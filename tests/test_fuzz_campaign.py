"""The cross-layer targets of ``make fuzz`` (tests/fuzz/paths.py), each run for a few seconds
so that CI exercises them, and their caps shown to fail a run (a target that grows, one that
never ends)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO
from fuzz.campaign import _run_path_target
from fuzz.path_drivers import SERIAL_CASES, internal_error, pty_emulator_class
from fuzz.path_vrpn import check_stderr
from fuzz.paths import CapExceeded, PathFailure, load

PATHS = load()
SHOWN = sorted(name for name, target in PATHS.items() if not target.hidden)
#: seconds each target runs here (the VRPN ones need a baseline before their attack)
SECONDS = {"vrpn.serve_hostile_client": 6.0, "vrpn.monitor_hostile_server": 7.0}


@pytest.mark.timeout(150)
@pytest.mark.parametrize("name", SHOWN)
def test_each_path_target_runs_within_its_caps(name: str) -> None:
    result = _run_path_target(name, SECONDS.get(name, 2.0), 24, 2048)
    assert not result.get("error"), f"{result['error']}\n{result.get('trace', '')}"
    figures = result["figures"]
    assert figures["peak_mb"] >= figures["baseline_mb"] > 0, figures
    if name.startswith("serial."):  # a pty stream mutated once the device runs, or sooner
        assert figures["frames"] > 0, figures
    else:  # at least a few bursts, however slow the start
        assert figures["inputs"] > 0, figures


def test_every_serial_driver_with_a_pty_emulator_has_a_path_target() -> None:
    drivers = sorted(p.name for p in (REPO / "drivers").iterdir() if (p / "emulator.py").is_file())
    with_pty = {d for d in drivers if pty_emulator_class(d) is not None}
    assert with_pty == {driver for driver, _ in SERIAL_CASES.values()}


@pytest.mark.timeout(120)
def test_a_target_that_grows_fails_the_campaign_by_its_memory_cap(tmp_path: Path) -> None:
    failures = tmp_path / "failures"
    done = subprocess.run(
        [sys.executable, "tests/fuzz/campaign.py", "--target", "selftest.grows",
         "--path-seconds", "20", "--seed", "5", "--failures", str(failures)],
        cwd=REPO, capture_output=True, text=True, timeout=100,
    )  # fmt: skip
    assert done.returncode == 1, done.stdout + done.stderr
    assert "memory cap exceeded: the target reached" in done.stdout
    saved = json.loads((failures / "selftest.grows-seed5.json").read_text())
    assert saved["target"] == "selftest.grows" and saved["seed"] == 5
    assert "memory cap exceeded" in saved["error"]
    assert saved["figures"]["peak_mb"] - saved["figures"]["baseline_mb"] > 63.8  # MB, rounded
    assert (failures / "selftest.grows-seed5.bin").is_file()
    replayed = subprocess.run(
        [sys.executable, "tests/fuzz/campaign.py", "--replay", str(failures / "selftest.grows-seed5.json")],
        cwd=REPO, capture_output=True, text=True, timeout=100,
    )  # fmt: skip
    assert replayed.returncode == 1, replayed.stdout + replayed.stderr
    assert "selftest.grows (seed 5): CapExceeded: memory cap exceeded" in replayed.stdout


@pytest.mark.timeout(60)
def test_a_target_that_never_ends_is_killed_by_its_time_cap() -> None:
    result = _run_path_target("selftest.hangs", 1.0, 0, 2048)
    assert result["error"].startswith("time cap exceeded: still running 3 s after it began")
    assert result["elapsed"] < 20


def test_a_fault_is_internal_when_python_raised_it() -> None:
    assert internal_error("IndexError: index 7 is out of bounds")
    assert internal_error("RecursionError: maximum recursion depth exceeded")
    assert internal_error("error: unpack requires a buffer of 24 bytes")  # struct.error
    assert not internal_error("FlockProtocolError: examine 0x03: 1413 bytes, not 2")
    assert not internal_error("TimeoutError: no answer")
    assert not internal_error("cannot open /dev/pts/9: No such file or directory")
    assert not internal_error(None)


@pytest.mark.parametrize(
    "text",
    [b"x" * 300_000, b"Traceback (most recent call last):\n", b"name \x1b[2J", b"bell \x07"],
)
def test_stderr_that_a_peer_could_have_written_fails(text: bytes) -> None:
    with pytest.raises(PathFailure):
        check_stderr("monitor", text)


def test_plain_stderr_passes() -> None:
    check_stderr("monitor", b"gadgetctl: problem: Tracker0: 3 bad messages\n")
    assert issubclass(CapExceeded, PathFailure)
