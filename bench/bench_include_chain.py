"""Issue 13 item 5 benchmark: a chain of 5,000 includes validates (iteratively) in under 2 s.

The target is on CPU time (user + system of the command), which a busy machine does not
inflate; on an idle machine the wall-clock time is the same figure plus a little I/O."""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from common import GADGETCTL, REPO, Report, command_cpu
from lxml import etree

sys.path.insert(0, str(REPO / "tests"))
from test_include_chains import write_include_chain

LENGTH = 5000


with tempfile.TemporaryDirectory() as tmp:
    first = write_include_chain(Path(tmp), LENGTH)
    files = sorted(Path(tmp).glob("*.jconf"))
    report = Report()
    print(f"include chain of {LENGTH} files")
    command_cpu([*GADGETCTL, "validate", str(first)])  # warm the file cache
    runs = [command_cpu([*GADGETCTL, "validate", str(first)]) for _ in range(3)]
    wall = sorted(r[0] for r in runs)[1]
    cpu = sorted(r[1] for r in runs)[1]
    start = time.perf_counter()
    parser = etree.XMLParser(resolve_entities=False, no_network=True)
    for path in files:
        etree.parse(str(path), parser)
    parse = time.perf_counter() - start
    startup = sorted(command_cpu([*GADGETCTL, "--version"])[0] for _ in range(3))[1]
    report.figure("validate the chain (wall clock, median of 3)", wall, "s")
    report.figure("validate the chain (CPU time, user + system)", cpu, "s", target=2)
    report.figure("lxml parse of the same files (baseline)", parse, "s")
    report.figure("gadgetctl --version (start-up baseline)", startup, "s")
    report.ratio("validate / lxml parse", wall, parse)
    report.exit()
