"""Checks before running (issue 16 item 4): monitor and replay --config print the configuration
findings as validate does before they start; errors stop the run only with --strict;
--no-check skips the checks; many findings end in one summary line."""

from __future__ import annotations

import io
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO

pytestmark = pytest.mark.timeout(120)

WAVEFORM = REPO / "examples" / "waveform.jconf"
HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="test">
<elements>
"""


def mistyped(tmp_path: Path, count: int = 1) -> Path:
    body = "".join(
        f'<waveform_device name="DT{i}" version="1"><rate>50.0</rate><sead>{i}</sead></waveform_device>\n'
        for i in range(count)
    )
    path = tmp_path / "typo.jconf"
    path.write_text(HEAD + body + "</elements>\n</configuration>\n")
    return path


def gadgetctl(*args: object) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "gadgetctl", *map(str, args)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=90,
    )


def test_a_mistyped_property_is_printed_before_the_monitor_starts(tmp_path):
    path = mistyped(tmp_path)
    done = gadgetctl("monitor", path, "--duration", "0.2", "--format", "table")
    assert done.returncode == 0, done.stderr
    assert f"{path}:5:" in done.stderr and "error CFG020" in done.stderr and "sead" in done.stderr
    assert "Did you mean seed?" in done.stderr
    assert "DT0" in done.stdout  # the run went on


def test_strict_stops_on_errors_and_no_check_skips_the_checks(tmp_path):
    path = mistyped(tmp_path)
    strict = gadgetctl("monitor", path, "--duration", "0.2", "--format", "table", "--strict")
    assert strict.returncode == 1 and "CFG020" in strict.stderr and "--strict" in strict.stderr
    assert "DT0" not in strict.stdout  # never started
    skipped = gadgetctl("monitor", path, "--duration", "0.2", "--format", "table", "--no-check")
    assert skipped.returncode == 0 and "CFG020" not in skipped.stderr


def test_many_findings_end_in_a_summary_line(tmp_path):
    path = mistyped(tmp_path, count=14)
    done = gadgetctl("monitor", path, "--duration", "0.2", "--format", "table")
    assert done.returncode == 0, done.stderr
    assert done.stderr.count("error CFG020") == 10
    assert (
        "… and 4 more: 14 errors, 0 warnings in all (gadgetctl validate --together" in done.stderr
    )


def test_replay_with_a_configuration_checks_it_first(tmp_path):
    recording = tmp_path / "run.ndjson"
    gadgetctl(
        "monitor", WAVEFORM, "--duration", "0.3", "--format", "ndjson", "--record", recording
    ).check_returncode()
    done = gadgetctl(
        "replay", recording, "--config", mistyped(tmp_path), "--format", "table", "--speed", "10"
    )
    assert "error CFG020" in done.stderr and "sead" in done.stderr
    assert "Waveform" in done.stdout  # the replay ran


def test_serve_checks_its_configuration_first(tmp_path):
    path = mistyped(tmp_path)
    done = gadgetctl("serve", path, "--list")
    assert done.returncode == 0, done.stderr
    assert "error CFG020" in done.stderr and "Did you mean seed?" in done.stderr
    assert "DT0" in done.stdout
    strict = gadgetctl("serve", path, "--list", "--strict")
    assert strict.returncode == 1 and "DT0" not in strict.stdout


def _summary(configuration) -> tuple:
    return (
        [(e.full_name, e.type, e.location.line) for e in configuration.elements],
        [(d.code, d.path, d.line, d.column, d.message) for d in configuration.diagnostics],
        [str(p) for p in configuration.roots],
    )


@pytest.mark.parametrize(
    "name",
    ["waveform.jconf", "all_devices.jconf", "c4_simulated_tracking.jconf"],
)
def test_the_run_loads_what_the_check_parsed_without_reading_it_again(name, monkeypatch):
    """Issue 27: monitor checked its configuration as validate does, then parsed every file
    again to run it (0.6 s of 10,000 devices). The documents the check parsed are now taken
    as they are: the same elements, diagnostics and includes, and no file read twice."""
    from gadgetctl.cli.preflight import check_before_running
    from gadgetctl.jccl import configload

    path = REPO / "examples" / name
    fresh = configload.load_configuration([path])
    parsed = check_before_running([path], stream=io.StringIO())
    assert parsed and all(doc.root is not None for doc in parsed.values())
    read: list[Path] = []
    real = configload.load_file
    monkeypatch.setattr(
        configload, "load_file", lambda p, **kw: read.append(Path(p)) or real(p, **kw)
    )
    reused = configload.load_configuration([path], parsed=parsed)
    assert _summary(reused) == _summary(fresh)
    assert path.resolve() not in read  # the checked file itself was not read again
    assert len(read) == len(fresh.files) - 1  # its includes were, once each


def test_problems_of_the_check_do_not_become_problems_of_loading(tmp_path):
    """A document the check parsed carries the check's findings (XML010 and on, schema);
    loading it reports only what reading the file found, as loading it afresh does."""
    from gadgetctl.cli.preflight import check_before_running
    from gadgetctl.jccl import configload

    path = tmp_path / "odd.jconf"
    # no format version processing instruction: a check finding (XML0xx), not a load error
    path.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="x">'
        '<elements><waveform_device name="W" version="1"><rate>10</rate></waveform_device>'
        "</elements></configuration>\n"
    )
    parsed = check_before_running([path], stream=io.StringIO())
    checked = parsed[path.resolve()].diagnostics
    assert any(d.code.startswith("XML01") for d in checked), [d.code for d in checked]
    reused = configload.load_configuration([path], parsed=parsed)
    assert _summary(reused) == _summary(configload.load_configuration([path]))


@pytest.mark.parametrize("name", ["waveform.jconf", "all_devices.jconf"])
def test_the_run_gets_the_checked_elements_without_the_checks_reports(name):
    """Issue 27 goal 3: the checks keep a report on each element they judge (findings,
    pointers, the view judged by); the elements the run is built from are handed over
    without them (the run never reads them: 20,000 reports, about 4 MB, lived to the end of
    a run of 10,000 devices). What the check found is printed all the same."""
    from gadgetctl.cli.preflight import check_before_running
    from gadgetctl.jccl import configload

    path = REPO / "examples" / name
    parsed = check_before_running([path], stream=io.StringIO())
    streamed = [e for doc in parsed.values() for b in doc.streamed or () for e in b.elements]
    assert streamed  # the elements read while parsing: the ones the run takes over
    configuration = configload.load_configuration([path], parsed=parsed)
    elements = list(configuration.all_elements())
    assert {id(e) for e in streamed} <= {id(e) for e in elements}
    assert all(e.report is None for e in elements)


def test_the_checks_findings_are_printed_although_their_reports_are_dropped(tmp_path):
    from gadgetctl.cli.preflight import check_before_running

    path = mistyped(tmp_path, count=3)
    out = io.StringIO()
    parsed = check_before_running([path], stream=out)
    assert out.getvalue().count("CFG020") == 3
    elements = [e for doc in parsed.values() for b in doc.streamed or () for e in b.elements]
    assert [e.name for e in elements] == ["DT0", "DT1", "DT2"]
    assert all(e.report is None for e in elements)
