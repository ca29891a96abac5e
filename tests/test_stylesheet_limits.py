"""Upgrade stylesheets from outside the bundled set run with bounded time and memory
(issue 13 item 2); the bundled ones keep running in-process."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from gadgetctl.jccl import xsltsandbox
from gadgetctl.jccl.repository import default_repository
from gadgetctl.jccl.upgrade import upgrade_bytes

from config_samples import XSL, configuration, definition, version

# A template that calls itself twice, 60 levels deep: 2^60 result nodes if nothing stops it.
EXPONENTIAL = (
    f'<xsl:stylesheet xmlns:xsl="{XSL}" version="1.0">'
    '<xsl:template match="/"><xsl:call-template name="f"><xsl:with-param name="n" select="60"/>'
    "</xsl:call-template></xsl:template>"
    '<xsl:template name="f"><xsl:param name="n"/><xsl:choose><xsl:when test="$n &gt; 0">'
    '<xsl:call-template name="f"><xsl:with-param name="n" select="$n - 1"/></xsl:call-template>'
    '<xsl:call-template name="f"><xsl:with-param name="n" select="$n - 1"/></xsl:call-template>'
    "</xsl:when><xsl:otherwise><x>" + "a" * 1000 + "</x></xsl:otherwise></xsl:choose>"
    "</xsl:template></xsl:stylesheet>"
)


def write_hostile_configuration(directory: Path) -> Path:
    """A configuration whose own <definition_path> brings a definition with the stylesheet."""
    (directory / "defs").mkdir()
    (directory / "defs" / "gizmo.jdef").write_text(
        definition("gizmo", version(1), version(2, transform=EXPONENTIAL))
    )
    path = directory / "hostile.jconf"
    path.write_text(
        configuration('      <gizmo name="G" version="1"/>\n').replace(
            "<elements>", "<definition_path><dir>defs</dir></definition_path>\n<elements>"
        )
    )
    return path


MEASURE = """
import resource, subprocess, sys
done = subprocess.run(sys.argv[1:], capture_output=True, text=True, timeout=40)  # kills it on expiry
peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024
print(done.returncode, peak, done.stderr.replace("\\n", " | "), sep="\\n")
"""


@pytest.mark.timeout(60)
def test_an_exponential_stylesheet_ends_with_a_diagnostic_in_bounded_memory(tmp_path):
    path = write_hostile_configuration(tmp_path)
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            MEASURE,
            sys.executable,
            "-m",
            "gadgetctl",
            "upgrade",
            "--check",
            str(path),
        ],
        capture_output=True,
        text=True,
        timeout=55,
    )
    code, peak, stderr = done.stdout.splitlines()
    assert int(code) == 1
    assert "CFG050" in stderr and str(tmp_path / "defs" / "gizmo.jdef") in stderr
    assert "time limit of 5 s" in stderr or "memory limit of 384 MB" in stderr
    assert int(peak) < 500 * 1024 * 1024, f"peak resident memory {int(peak) >> 20} MB"


def test_the_sandbox_reports_the_stylesheets_own_errors(tmp_path):
    broken = f'<xsl:stylesheet xmlns:xsl="{XSL}" version="1.0"><xsl:template match="/"/></xsl:stylesheet>'
    (tmp_path / "defs").mkdir()
    (tmp_path / "defs" / "gizmo.jdef").write_text(
        definition("gizmo", version(1), version(2, transform=broken))
    )
    repo = default_repository([tmp_path / "defs"], bundled=False)
    result = upgrade_bytes(
        tmp_path / "g.jconf", configuration('      <gizmo name="G" version="1"/>\n').encode(), repo
    )
    assert result.upgraded is None and result.problems[0].code == "CFG050"
    assert "produced no element" in result.problems[0].message
    assert (
        xsltsandbox._child is not None and xsltsandbox._child.alive()
    )  # ran there, and stays for the next


def test_bundled_stylesheets_run_in_process(tmp_path, corpus):
    xsltsandbox._stop_child()
    old = corpus / "modules" / "vrjuggler" / "data" / "configFiles" / "example.vrpn.jconf"
    result = upgrade_bytes(old, old.read_bytes(), default_repository([]))
    assert result.changed and not result.problems
    assert xsltsandbox._child is None, "a bundled stylesheet started the sandbox"
