"""Issue 13 item 2 benchmark: bundled upgrade stylesheets keep their in-process speed; one
from elsewhere runs in the limited child process; a hostile one ends within 10 s in under
500 MB."""

from __future__ import annotations

import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import CORPUS, GADGETCTL, REPO, Report, median_time

from gadgetctl.jccl.repository import default_repository
from gadgetctl.jccl.upgrade import upgrade_bytes

sys.path.insert(0, str(REPO / "tests"))
from test_stylesheet_limits import write_hostile_configuration

DATA = CORPUS / "modules" / "vrjuggler" / "data"
files = [(p, p.read_bytes()) for p in sorted((DATA / "configFiles").glob("*.jconf"))]
bundled = default_repository([])
elsewhere = default_repository([DATA / "definitions"], bundled=False)


def upgrade_all(repo) -> int:
    return sum(len(upgrade_bytes(path, data, repo).elements) for path, data in files)


report = Report()
elements = upgrade_all(bundled)
upgrade_all(elsewhere)  # start the child once
print(f"{len(files)} corpus configurations, {elements} elements to upgrade")
inside = median_time(lambda: upgrade_all(bundled), repeat=5)
child = median_time(lambda: upgrade_all(elsewhere), repeat=5)
report.figure("bundled definitions (in-process)", inside * 1000, "ms")
report.figure("the corpus's own definitions (limited child process)", child * 1000, "ms")
report.ratio("child process / in-process", child, inside)

with tempfile.TemporaryDirectory() as tmp:
    hostile = write_hostile_configuration(Path(tmp))
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    start = time.perf_counter()
    done = subprocess.run(
        [*GADGETCTL, "upgrade", "--check", str(hostile)], capture_output=True, text=True
    )
    took = time.perf_counter() - start
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    assert done.returncode == 1 and "CFG050" in done.stderr, done.stderr
    report.figure("exponential stylesheet: upgrade --check ends after", took, "s", target=10)
    report.figure(
        "  peak resident memory of a process it ran", max(peak, before) / 1024, "MB", target=500
    )
report.exit()
