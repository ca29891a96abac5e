"""`gadgetctl validate` read without typer (issue 27 goal 4) reads a command line as typer
does, or leaves it to typer: the options are the typer command's, and for any command line
it accepts, the arguments are those typer passes."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
import typer.main
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gadgetctl.cli import validate_cmd
from gadgetctl.cli.app import build_app
from gadgetctl.cli.validate_fast import COMPLETE_VAR, FLAGS, VALUE_OPTIONS, parse

NAMES = [
    "paths",
    "fmt",
    "strict",
    "definitions",
    "bundled",
    "together",
    "level",
    "max_size",
    "hints",
    "color",
]


def _typer_reading(words: list[str], monkeypatch) -> dict | None:
    """What typer passes to run_validate for ``validate WORDS``; None on a usage error."""
    seen: list[tuple] = []
    monkeypatch.setattr(validate_cmd, "run_validate", lambda *args: seen.append(args))
    try:
        build_app("validate")(
            args=["validate", *words], prog_name="gadgetctl", standalone_mode=False
        )
    except Exception:  # a usage error (Click's exceptions)
        return None
    return dict(zip(NAMES, seen[0], strict=True)) if seen else None


def _same(fast: dict, slow: dict) -> None:
    assert list(fast["paths"]) == list(slow["paths"])
    assert list(fast["definitions"]) == list(slow["definitions"])
    for name in NAMES:
        if name not in ("paths", "definitions"):
            assert fast[name] == slow[name] and type(fast[name]) is type(slow[name]), name


def test_the_options_are_the_typer_command_s():
    command = typer.main.get_command(build_app("validate")).commands["validate"]
    values, flags = {}, {}
    for param in command.params:
        if param.param_type_name != "option":
            assert param.name == "paths"
            continue
        if param.is_flag:
            for opt in param.opts:
                flags[opt] = (param.name, True)
            for opt in param.secondary_opts:
                flags[opt] = (param.name, False)
        else:
            for opt in param.opts:
                values[opt] = param.name
    assert values == VALUE_OPTIONS
    assert flags == FLAGS


@pytest.mark.parametrize(
    "words",
    [
        ["a.jconf"],
        ["a.jconf", "b", "-f", "json"],
        ["--format=sarif", "a", "--strict", "--together", "--no-hints", "--hints", "--no-hints"],
        ["-d", "defs", "a", "--definitions", "more", "--definitions=x", "--no-bundled"],
        ["a", "--level", "schema", "--level=xml", "--max-size", "100", "--color", "never"],
        ["a", "-f", "github", "-f", "text", "--color=always", "--bundled", "--max-size=1"],
    ],
)
def test_command_lines_read_as_typer_reads_them(words, monkeypatch):
    fast = parse(words, {})
    assert fast is not None
    slow = _typer_reading(words, monkeypatch)
    assert slow is not None
    _same(fast, slow)


@pytest.mark.parametrize(
    "words",
    [
        [],
        ["--help"],
        ["a", "-h"],
        ["a", "--format"],
        ["a", "--format", "JSON"],
        ["a", "--format="],
        ["a", "-fjson"],
        ["a", "-f=json"],
        ["a", "--form", "json"],
        ["a", "--max-size", "0"],
        ["a", "--max-size", "1_000"],
        ["a", "--max-size", " 5"],
        ["a", "--strict=1"],
        ["a", "--", "b"],
        ["-", "a"],
        ["a", "-d", "-x"],
        [""],
        ["a\0b"],
    ],
)
def test_other_command_lines_are_left_to_typer(words):
    assert parse(words, {}) is None


def test_shell_completion_is_left_to_typer():
    assert parse(["a"], {COMPLETE_VAR: "bash_complete"}) is None


def test_windows_is_left_to_typer(monkeypatch):
    monkeypatch.setattr(os, "name", "nt")  # (Click expands wildcards there)
    assert parse(["a"], {}) is None


def test_an_unreadable_path_is_left_to_typer(tmp_path, monkeypatch):
    secret = tmp_path / "secret.jconf"
    secret.write_text("<configuration/>")
    readable = os.access
    # as for a user the file's mode refuses (root reads any file, and CI runs as root)
    monkeypatch.setattr(
        os, "access", lambda path, mode: False if str(path) == str(secret) else readable(path, mode)
    )
    assert parse([str(secret)], {}) is None
    assert parse([str(tmp_path)], {}) is not None
    assert parse([str(tmp_path / "missing.jconf")], {}) is not None


_WORDS = st.lists(
    st.sampled_from(
        [
            *VALUE_OPTIONS,
            *FLAGS,
            "a.jconf",
            "dir",
            "json",
            "text",
            "sarif",
            "full",
            "xml",
            "never",
            "always",
            "7",
            "0",
            "-x",
            "--format=json",
            "--level=schema",
            "--definitions=d",
            "--max-size=3",
            "--color=auto",
            "--help",
            "--",
        ]
    ),
    max_size=8,
)


@settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(words=_WORDS)
def test_what_is_read_without_typer_is_what_typer_reads(words, monkeypatch):
    fast = parse(words, {})
    if fast is None:
        return
    slow = _typer_reading(words, monkeypatch)
    assert slow is not None, words
    _same(fast, slow)


@pytest.mark.timeout(60)
def test_the_validate_process_does_not_import_typer(tmp_path):
    (tmp_path / "a.jconf").write_text("<configuration/>", encoding="utf-8")
    code = (
        "import os, sys\n"
        "from gadgetctl.cli import exiting\n"
        "def finish(code):\n"
        "    sys.stdout.flush()\n"
        "    import gc\n"
        "    assert not gc.isenabled() and collections() == before  # none since run()\n"
        "    sys.stderr.write(' '.join(m for m in ('typer', 'click') if m in sys.modules))\n"
        "    sys.stderr.flush()\n"
        "    os._exit(code)\n"
        "exiting.finish = finish\n"
        "from gadgetctl.cli.main import run\n"
        "import gc\n"
        "def collections():\n"
        "    return sum(generation['collections'] for generation in gc.get_stats())\n"
        "before = collections()\n"
        "sys.argv = ['gadgetctl', 'validate', sys.argv[1], '-f', 'json']\n"
        "run()\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code, str(tmp_path)], capture_output=True, text=True, timeout=60
    )
    assert done.stderr == ""
    assert done.returncode == 1 and '"code": "SCH001"' in done.stdout
    typer_done = subprocess.run(
        [sys.executable, "-m", "gadgetctl", "validate", str(tmp_path), "-f", "json", "--help"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert typer_done.returncode == 0 and "Usage: gadgetctl validate" in typer_done.stdout


def test_same_output_and_status_with_and_without_typer(tmp_path):
    (tmp_path / "bad.jconf").write_text("<configuration><elements><x", encoding="utf-8")
    (tmp_path / "ok.jdef").write_text("<definition/>", encoding="utf-8")
    fast = subprocess.run(
        [sys.executable, "-m", "gadgetctl", "validate", str(tmp_path), "-f", "json"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    env = {**os.environ, COMPLETE_VAR: ""}  # (typer reads it: no completion asked for)
    slow = subprocess.run(
        [sys.executable, "-m", "gadgetctl", "validate", str(tmp_path), "-f", "json"],
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
    )
    assert (fast.returncode, fast.stdout, fast.stderr) == (
        slow.returncode,
        slow.stdout,
        slow.stderr,
    )
    assert fast.returncode == 1 and Path(tmp_path / "bad.jconf").name in fast.stdout
