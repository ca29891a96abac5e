"""How closely `gadgetctl replay --speed X` keeps to the recording's time, scaled.

Two seconds of examples/waveform.jconf (about 8,000 samples) are recorded, then replayed
with `--format ndjson` at speed 1 and 10. The span from the first replayed sample to the
end record is compared with the recording's span divided by the speed: the replay must
neither lag (samples encoded more slowly than they fall due) nor linger after the end.
The replayed samples' relative timestamps are exact by construction (tests check that);
this is the wall-clock side, which depends on the machine and so lives here.

Run from the repository root: python bench/bench_replay.py
Exit status 1 when a target is missed.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

from common import GADGETCTL, REPO, Report

WAVEFORM = REPO / "examples" / "waveform.jconf"
RECORDED_SPAN = 2.0


def replay_span(path: Path, speed: float) -> float:
    done = subprocess.run(
        [*GADGETCTL, "replay", str(path), "--speed", str(speed), "--format", "ndjson"],
        capture_output=True,
        text=True,
        check=True,
        cwd=REPO,
    )
    records = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    first = min(r["timestamp"] for r in records if r["type"] == "sample")
    return records[-1]["timestamp"] - first


def main() -> int:
    report = Report()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "waveform.ndjson"
        subprocess.run(
            [
                *GADGETCTL,
                "monitor",
                str(WAVEFORM),
                "--duration",
                str(RECORDED_SPAN),
                "--format",
                "table",
                "--interval",
                "10",
                "--record",
                str(path),
            ],
            capture_output=True,
            check=True,
            cwd=REPO,
        )
        for speed in (1.0, 10.0):
            expected = RECORDED_SPAN / speed
            span = min(replay_span(path, speed) for _ in range(3))
            report.figure(
                f"replay --speed {speed:g}: first sample to end record",
                span,
                "s",
                target=expected + 0.12 + 0.05 * expected,
            )
            report.ratio(
                f"replay --speed {speed:g}: span against the scaled recording", span, expected
            )
    report.exit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
