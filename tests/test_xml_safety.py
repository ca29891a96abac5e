"""Hostile and broken inputs: bounded, offline, one diagnostic each, never a traceback."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import time

import pytest

from gadgetctl.jccl.xmlload import load_file
from gadgetctl.validate import validate_paths

from conftest import write
from jccl_samples import jconf


def codes(path):
    return [(d.code, d.line) for d in validate_paths([path]).diagnostics]


def test_not_well_formed_reports_line_and_column(tmp_path):
    path = write(tmp_path / "bad.jconf", jconf('      <alias name="a" version="1">\n'))
    (diag,) = validate_paths([path]).diagnostics
    assert diag.code == "XML001"
    assert diag.line == 6 and diag.column is not None
    assert "alias" in diag.message


def test_external_entity_is_not_expanded(tmp_path):
    secret = write(tmp_path / "secret.txt", "TOP-SECRET")
    text = jconf('      <alias name="&x;" version="1"/>\n').replace(
        "<configuration",
        f'<!DOCTYPE configuration [<!ENTITY x SYSTEM "file://{secret}">]>\n<configuration',
    )
    path = write(tmp_path / "xxe.jconf", text)
    doc = load_file(path)
    assert (
        b"TOP-SECRET" not in __import__("lxml.etree").etree.tostring(doc.root)
        if doc.root is not None
        else True
    )
    found = validate_paths([path]).diagnostics
    assert any(d.code == "XML003" for d in found)
    assert all("TOP-SECRET" not in d.message for d in found)


def test_billion_laughs_is_bounded(tmp_path):
    entities = '<!ENTITY a0 "lol">' + "".join(
        f'<!ENTITY a{i} "{f"&a{i - 1};" * 10}">' for i in range(1, 10)
    )
    text = jconf("      <x>&a9;</x>\n").replace(
        "<configuration", f"<!DOCTYPE configuration [{entities}]>\n<configuration"
    )
    path = write(tmp_path / "lol.jconf", text)
    start = time.perf_counter()
    found = validate_paths([path]).diagnostics
    assert time.perf_counter() - start < 10  # expanded, the entities would be 3 GB of text
    assert any(d.code == "XML003" for d in found)


def test_deep_nesting_is_refused(tmp_path):
    path = tmp_path / "deep.jconf"
    path.write_bytes(b"<configuration>" + b"<a>" * 50000 + b"</a>" * 50000 + b"</configuration>")
    (diag,) = validate_paths([path]).diagnostics
    assert diag.code == "XML001" and "depth" in diag.message.lower()


def test_huge_file_is_not_read(tmp_path):
    path = tmp_path / "huge.jconf"
    with path.open("wb") as f:
        f.truncate(100 * 1024 * 1024)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    start = time.perf_counter()
    (diag,) = validate_paths([path]).diagnostics
    assert diag.code == "XML004"
    assert time.perf_counter() - start < 5  # a hang guard; the memory bound below is the test
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 50 * 1024  # KiB


@pytest.mark.timeout(30)
def test_hostile_file_through_the_cli_has_no_traceback(tmp_path):
    path = tmp_path / "x.jconf"
    path.write_bytes(b"<configuration>" + b"<a>" * 5000)
    proc = subprocess.run(
        [sys.executable, "-m", "gadgetctl", "validate", str(path)],
        capture_output=True,
        text=True,
        timeout=20,
        env={**os.environ, "NO_COLOR": "1"},
    )
    assert proc.returncode == 1
    assert "Traceback" not in proc.stderr + proc.stdout
    assert f"{path}:1:" in proc.stdout


def test_declared_latin1_is_fine(tmp_path):
    path = tmp_path / "latin.jconf"
    path.write_bytes(
        jconf('      <alias name="caf\xe9" version="1"/>\n')
        .replace('encoding="UTF-8"', 'encoding="ISO-8859-1"')
        .encode("latin-1")
    )
    assert not [c for c, _ in codes(path) if c.startswith("XML")]


def test_unknown_root_element(tmp_path):
    path = write(tmp_path / "other.xml.jconf", '<?xml version="1.0"?>\n<config name="x"/>\n')
    assert ("XML014", 2) in codes(path)


def test_kind_falls_back_on_root_element(tmp_path):
    from gadgetctl.jccl.xmlload import FileKind

    path = write(tmp_path / "noext.xml", jconf())
    assert load_file(path).kind is FileKind.CONFIGURATION
