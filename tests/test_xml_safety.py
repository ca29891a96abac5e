"""Hostile and broken inputs: bounded, offline, one diagnostic each, never a traceback."""

from __future__ import annotations

import contextlib
import os
import resource
import shutil
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


# -- internal entities and unreadable paths (issue 24 item 8) --------------------------------------

ENTITY_FILE = """<?xml version="1.0" encoding="UTF-8"?>
<!DOCTYPE configuration [ <!ENTITY port "6000"> <!ENTITY quote '">'> ]>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="t">
   <elements>
      <motion_star name="S&port;" version="2">
         <server_port>&port;</server_port>
      </motion_star>
   </elements>
</configuration>
"""


def test_an_internal_entity_is_xml003_where_it_is_used_and_never_expanded(tmp_path, cli):
    from gadgetctl.jccl.configload import load_configuration

    path = write(tmp_path / "entity.jconf", ENTITY_FILE)
    result = cli("validate", path)
    assert result.exit_code == 1 and "internal error" not in result.stderr, result.stderr
    from gadgetctl.validate import ValidateOptions

    for level in ("full", "xml"):
        found = validate_paths([path], ValidateOptions(level=level)).diagnostics
        places = sorted((d.line, d.column) for d in found if d.code == "XML003" and d.line > 2)
        assert places == [(5, 27), (6, 23)], found  # the attribute's and the content's
    (element,) = load_configuration([path]).elements
    assert element.name == "S"  # not S6000: the entity in the attribute is not expanded


NO_DAC = """
import ctypes, sys
libc = ctypes.CDLL(None, use_errno=True)
header = (ctypes.c_uint32 * 2)(0x20080522, 0)  # _LINUX_CAPABILITY_VERSION_3, this process
sets = (ctypes.c_uint32 * 6)()
assert libc.capget(header, sets) == 0
for i in range(3):  # effective, permitted, inheritable: without DAC override and read search
    sets[i] &= ~((1 << 1) | (1 << 2)) & 0xFFFFFFFF
assert libc.capset(header, sets) == 0
from gadgetctl.cli.main import main
main(sys.argv[1:])
"""


def _without_permission_override(*args) -> subprocess.CompletedProcess:
    """``gadgetctl ARGS`` in a process that file permissions bind even when run as root (CI):
    it drops the capabilities that override them."""
    return subprocess.run(
        [sys.executable, "-c", NO_DAC, *map(str, args)],
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )


@pytest.mark.parametrize("command", [["validate"], ["upgrade", "--check"]])
def test_unreadable_places_are_one_line_each(tmp_path, command):
    closed = tmp_path / "closed"
    closed.mkdir()
    write(closed / "inside.jconf", jconf())
    write(tmp_path / "open.jconf", jconf())
    closed.chmod(0)
    try:
        cases = {
            closed / "inside.jconf": f"{closed / 'inside.jconf'}: cannot look it up: Permission denied",
            tmp_path: f"{closed}: directory is not readable (Permission denied); the files in it cannot be checked",
        }  # fmt: skip
        for path, line in cases.items():
            result = _without_permission_override(*command, path)
            assert (result.returncode, result.stderr) == (2, f"gadgetctl: error: {line}\n")
    finally:
        closed.chmod(0o755)


def test_a_folder_removed_while_the_walk_is_under_way_is_skipped(tmp_path, monkeypatch):
    """A build's temporary folder can be gone between listing its parent and reading it: it
    holds nothing to check, and the walk goes on (it stopped the whole run before)."""
    from gadgetctl.files import expand_paths

    write(tmp_path / "kept" / "a.jconf", jconf())
    doomed = tmp_path / "tmp-build"
    write(doomed / "b.jconf", jconf())
    real_scandir = os.scandir

    def scandir_then_remove(path):
        if path != os.fspath(tmp_path):
            return real_scandir(path)
        with real_scandir(path) as listing:
            entries = list(listing)
        shutil.rmtree(doomed)  # the parent is listed: the folder goes before it is read
        return contextlib.nullcontext(entries)

    monkeypatch.setattr(os, "scandir", scandir_then_remove)
    assert expand_paths([tmp_path]) == [tmp_path / "kept" / "a.jconf"]


def test_the_folder_named_itself_still_has_to_be_readable(tmp_path, monkeypatch):
    from gadgetctl.errors import GadgetctlError
    from gadgetctl.files import expand_paths

    write(tmp_path / "a.jconf", jconf())
    real_scandir = os.scandir

    def gone(path):
        if path == os.fspath(tmp_path):
            raise FileNotFoundError(2, "No such file or directory", os.fspath(path))
        return real_scandir(path)

    monkeypatch.setattr(os, "scandir", gone)
    with pytest.raises(GadgetctlError, match="directory is not readable"):
        expand_paths([tmp_path])
