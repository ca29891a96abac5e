"""`gadgetctl --help` is printed from the text typer renders, without importing typer
(issue 27 goal 4); the text kept must be what typer prints now."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from gadgetctl.cli import roothelp
from gadgetctl.cli.roothelp_text import TEXT


def test_the_root_help_kept_is_what_typer_prints():
    assert roothelp.render() == TEXT, (
        "src/gadgetctl/cli/roothelp_text.py is stale: run `make completions`"
    )


@pytest.mark.timeout(60)
@pytest.mark.parametrize("option", ["--help", "-h"])
def test_help_is_answered_without_the_cli_framework(option):
    code = (
        f"import sys; from gadgetctl.cli.main import main; main([{option!r}]); "
        "sys.stderr.write(' '.join(m for m in ('typer', 'click', 'rich') if m in sys.modules))"
    )
    env = {**os.environ, "COLUMNS": "100"}
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=60
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout == TEXT
    assert done.stderr == ""  # none of them was imported


@pytest.mark.timeout(60)
def test_a_narrow_terminal_gets_typer_s_own_wrapping():
    env = {**os.environ, "COLUMNS": "60"}
    done = subprocess.run(
        [sys.executable, "-m", "gadgetctl", "--help"],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout != TEXT and done.stdout.startswith("Usage: gadgetctl")
    assert max(len(line) for line in done.stdout.splitlines()) <= 60
