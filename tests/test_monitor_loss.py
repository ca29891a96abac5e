"""`monitor` ends with exit status 1 and one line saying what was lost when a device lost data
during the run (here: samples over the per-frame cap, which a 20 kHz waveform device read at
2 frames a second exceeds every frame), and 0 with ``--accept-loss`` (issue 23, item 4)."""

from __future__ import annotations

from pathlib import Path

import pytest

from gadgetctl.input.testing.commands import run_gadgetctl

pytestmark = pytest.mark.timeout(120)

FAST = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="fast">
  <elements>
    <waveform_device name="Fast" version="1">
      <rate>20000.0</rate>
      <analog_waveform>sine</analog_waveform>
      <analog_frequency>1.0</analog_frequency>
      <event_period>0.0</event_period>
    </waveform_device>
  </elements>
</configuration>
"""


def monitor(config: Path, *extra: str):
    return run_gadgetctl(
        "monitor", str(config), "--rate", "2", "--duration", "1.2", "--format", "table",
        "--no-check", *extra, timeout=100,
    )  # fmt: skip


def test_lost_samples_end_the_run_with_1_and_the_reason_unless_loss_is_accepted(
    tmp_path: Path,
) -> None:
    config = tmp_path / "fast.jconf"
    config.write_text(FAST)
    lost = monitor(config)
    assert lost.returncode == 1, lost.stderr[-2000:]
    problems = [line for line in lost.stderr.splitlines() if line.startswith("gadgetctl: problem")]
    assert len(problems) == 1, lost.stderr
    assert problems[0].startswith("gadgetctl: problem: Fast: lost data: ")
    assert "samples over the per-frame cap of 5000 (--accept-loss accepts loss)" in problems[0]
    accepted = monitor(config, "--accept-loss")
    assert accepted.returncode == 0, accepted.stderr[-2000:]
    assert "problem" not in accepted.stderr


def test_the_option_is_documented_in_the_help() -> None:
    done = run_gadgetctl("monitor", "--help", env={"COLUMNS": "200"})
    assert done.returncode == 0 and "--accept-loss" in done.stdout
    docs = (Path(__file__).resolve().parents[1] / "docs" / "monitor.md").read_text()
    assert "`--accept-loss`" in docs
