"""A finished `gadgetctl validate` ends its own process at once (gadgetctl.cli.exiting):
nothing it prints may be lost on the way, and in-process callers are never ended."""

from __future__ import annotations

import subprocess
import sys

import pytest
import typer
from test_validate_scale import HEAD, TAIL, alias_chain

from gadgetctl import perf
from gadgetctl.cli import exiting


@pytest.mark.timeout(120)
def test_a_validation_ending_its_process_prints_everything_the_in_process_one_prints(tmp_path, cli):
    path = tmp_path / "chain.jconf"
    path.write_text(HEAD + alias_chain(3_000) + TAIL)
    for fmt in ("text", "json"):
        inside = cli("validate", path, "--format", fmt)
        done = subprocess.run(
            [sys.executable, "-m", "gadgetctl", "validate", str(path), "--format", fmt],
            capture_output=True,
            text=True,
            timeout=100,
        )
        assert (done.returncode, done.stdout, done.stderr) == (1, inside.stdout, inside.stderr)
        assert inside.exit_code == 1 and "CFG032" in done.stdout


@pytest.mark.timeout(60)
def test_a_reader_that_stops_early_gets_no_traceback(tmp_path):
    path = tmp_path / "chain.jconf"
    path.write_text(HEAD + alias_chain(3_000, end="A0") + TAIL)  # a waiting cycle: many lines
    with subprocess.Popen(
        [sys.executable, "-m", "gadgetctl", "validate", str(path), "--format", "json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    ) as process:
        assert process.stdout.read(10)
        process.stdout.close()
        error = process.stderr.read().decode()
        assert process.wait(timeout=50) in (1, 2)
    assert "Traceback" not in error


def test_in_process_callers_get_typer_exit_and_keep_their_memory():
    assert not exiting.own_process
    with pytest.raises(typer.Exit) as ended:
        exiting.finish(1)
    assert ended.value.exit_code == 1
    kept = object()
    perf.retain(kept)
    assert perf._retained is None  # nothing is held back for a process that goes on


def test_the_collector_comes_back_on_after_bulk_work_in_a_process_that_goes_on():
    import gc

    from gadgetctl.perf import collector_paused

    assert gc.isenabled()
    with collector_paused():
        assert not gc.isenabled()
    assert gc.isenabled()


def test_what_is_built_to_last_is_left_out_of_later_collections():
    import gc

    from gadgetctl.perf import built_to_last

    assert gc.isenabled()
    frozen = gc.get_freeze_count()
    try:
        with built_to_last():
            assert not gc.isenabled()
            kept = [[] for _ in range(1000)]
        assert gc.isenabled()
        assert gc.get_freeze_count() >= frozen + len(kept)
        assert gc.get_count()[0] < len(kept)  # not waiting for the next collection's walk
    finally:
        gc.unfreeze()  # (this process goes on)


def test_a_monitor_in_process_sets_nothing_aside(tmp_path, cli):
    import gc

    path = tmp_path / "w.jconf"
    path.write_text(
        HEAD + '<waveform_device name="W" version="1"><rate>10</rate></waveform_device>\n' + TAIL
    )
    frozen = gc.get_freeze_count()
    result = cli("monitor", str(path), "--duration", "0.1", "--format", "table")
    assert result.exit_code == 0, result.output
    assert gc.get_freeze_count() == frozen
