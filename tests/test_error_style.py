"""One error style everywhere (issue 25 item 7): an option or argument error is one line,
``gadgetctl: error: COMMAND: what is wrong (see 'gadgetctl COMMAND --help')``, exit status 2,
naming the option or argument at fault; ``--help`` stays the place for the usage."""

from __future__ import annotations

import pytest

from conftest import REPO

WAVEFORM = REPO / "examples" / "waveform.jconf"

CASES = [
    (("validate", "--bogus", "x"), "validate: no such option: --bogus"),
    (("validate",), "validate: missing argument 'PATHS...'"),
    (("monitor", WAVEFORM, "--format", "nope"), "monitor: invalid value for '--format'"),
    (("monitor", WAVEFORM, "--duration", "abc"), "monitor: invalid value for '--duration'"),
    (("defs", "show"), "defs show: missing argument 'TYPE'"),
    (("config", "show", "--element"), "config show: option '--element' requires an argument"),
    (("nosuch",), "no such command 'nosuch'"),
    (("emulate", "DTrack_drv", "--bogus"), "emulate DTrack_drv: unrecognized arguments: --bogus"),
]


@pytest.mark.parametrize(
    ("args", "message"),
    CASES,
    ids=lambda v: " ".join(map(str, v)) if isinstance(v, tuple) else None,
)
def test_an_option_error_is_one_line_naming_the_option(cli, args, message):
    result = cli(*args)
    assert result.exit_code == 2
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith(f"gadgetctl: error: {message}"), lines[0]
    command = " ".join(str(a) for a in args[: 2 if args[0] in ("defs", "config", "emulate") else 1])
    help_path = "gadgetctl" if args[0] == "nosuch" else f"gadgetctl {command}"
    assert lines[0].endswith(f"(see '{help_path} --help')")
    assert "Usage:" not in result.stderr and "Try '" not in result.stderr


def test_help_still_shows_the_usage(cli):
    result = cli("validate", "--help")
    assert result.exit_code == 0
    assert result.stdout.startswith("Usage: gadgetctl validate [OPTIONS] PATHS...")


def test_a_group_without_its_command_shows_its_help(cli):
    result = cli("config")
    assert result.exit_code == 2
    assert "Commands:" in result.stdout + result.stderr
