"""`gadgetctl monitor --format table | head -1` ends with exit status 0, as events and ndjson
do (issue 25 item 6): a reader that went away has what it wanted."""

from __future__ import annotations

import subprocess
import sys

import pytest

from conftest import REPO

pytestmark = pytest.mark.timeout(60)


@pytest.mark.parametrize("fmt", ["table", "events", "ndjson"])
def test_a_reader_that_goes_away_is_no_error(fmt):
    child = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "gadgetctl",
            "monitor",
            REPO / "examples" / "waveform.jconf",
            "--format",
            fmt,
            "--interval",
            "0.1",
            "--duration",
            "20",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        cwd=REPO,
    )
    try:
        assert child.stdout.readline()  # what `head -1` reads
        child.stdout.close()
        code = child.wait(timeout=30)  # the next write finds the pipe closed
        assert code == 0, child.stderr.read().decode()
        assert b"Traceback" not in child.stderr.read()
    finally:
        child.kill()
        child.wait()
