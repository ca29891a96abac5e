"""Issue 16 item 9: the small things a new user trips over.

Plurals, argument names in usage lines, the `completion` help line, emulator usage and
`--scenario` help, the `--rate 0` message, /FRAME and RATE over one window, and the
scaffolded driver's next steps saying how to get pytest.
"""

from __future__ import annotations

import re

import pytest

from gadgetctl.monitor.stats import DeviceSnapshot, DeviceStats
from gadgetctl.wording import counted

from conftest import REPO

# --- plurals -------------------------------------------------------------------------------


def test_counted_chooses_the_number():
    assert counted(1, "file") == "1 file"
    assert counted(0, "file") == "0 files"
    assert counted(2, "proxy", "proxies") == "2 proxies"
    assert counted(1, "proxy", "proxies") == "1 proxy"


def test_one_of_a_thing_is_singular(cli, tmp_path):
    one = REPO / "examples" / "waveform.jconf"
    assert cli("validate", one).stdout.splitlines()[-1] == "1 file checked: no problems found"
    assert (
        cli("upgrade", "--check", one).stdout.splitlines()[-1] == "1 file checked: all up to date"
    )
    assert (
        cli("defs", "list", "--base", "waveform_device").stdout.splitlines()[-1] == "1 definition"
    )
    broken = tmp_path / "broken.jconf"
    broken.write_text("<configuration><elements>")
    result = cli("validate", broken)
    assert result.exit_code == 1
    assert result.stdout.splitlines()[-1] == "1 file checked: 1 error, 0 warnings in 1 file"


def test_no_message_writes_a_plural_in_parentheses():
    """'(s)' reads as if the program could not count: every message says 1 thing or 2 things."""
    offenders = []
    for path in sorted((REPO / "src" / "gadgetctl").rglob("*.py")):
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if re.search(r"""f["'].*[a-z]\(s\)""", line):
                offenders.append(f"{path.relative_to(REPO)}:{number}: {line.strip()}")
    assert offenders == []


# --- usage lines and help --------------------------------------------------------------------

USAGES = {
    ("validate",): "Usage: gadgetctl validate [OPTIONS] PATHS...",
    ("upgrade",): "Usage: gadgetctl upgrade [OPTIONS] PATHS...",
    ("completion",): "Usage: gadgetctl completion [OPTIONS] SHELL",
    ("explain",): "Usage: gadgetctl explain [OPTIONS] [CODE]",
    ("config", "show"): "Usage: gadgetctl config show [OPTIONS] FILES...",
    ("config", "pending"): "Usage: gadgetctl config pending [OPTIONS] FILES...",
    ("monitor",): "Usage: gadgetctl monitor [OPTIONS] CONFIG... [NAME...]",
    ("defs", "show"): "Usage: gadgetctl defs show [OPTIONS] TYPE",
}


@pytest.mark.parametrize("command", list(USAGES), ids=" ".join)
def test_usage_lines_name_arguments_by_their_metavar(cli, command):
    assert cli(*command, "--help").stdout.splitlines()[0] == USAGES[command]


def test_no_usage_or_option_shows_typer_type_names(cli):
    """Every command's help: no `{name}`, no `name:<choices>`, no `<str>`-style metavars."""
    import typer.main

    from gadgetctl.cli.app import build_app

    def walk(command, path):
        if getattr(command, "commands", None):
            for name, sub in command.commands.items():
                yield from walk(sub, [*path, name])
        else:
            yield path

    for path in walk(typer.main.get_command(build_app()), []):
        text = cli(*path, "--help").stdout
        assert not re.search(r"\{|:<|<(str|int|float|path)>", text), (path, text)


def test_completion_help_line(cli):
    listing = cli("--help").stdout
    line = next(line for line in listing.splitlines() if line.strip().startswith("completion "))
    assert line.split(None, 1)[1] == "Print the completion script for bash, zsh or fish."
    text = cli("completion", "--help").stdout
    assert "gadgetctl completion zsh > ~/.zfunc/_gadgetctl" in text
    assert "SHELL  The shell to complete for: bash, zsh or fish." in text


# --- emulators -------------------------------------------------------------------------------


@pytest.mark.parametrize("driver", ["DTrack_drv", "Flock_drv", "PinchGlove_drv"])
def test_emulator_usage_names_the_command_and_explains_scenarios(cli, driver):
    result = cli("emulate", driver, "--help")
    assert result.exit_code == 0
    assert result.stdout.startswith(f"usage: gadgetctl emulate {driver} ")
    help_text = " ".join(result.stdout.split())
    assert re.search(r"--scenario NAME what to send \(default \w+\): idle: ", help_text)
    assert "garbage: motion with junk and broken records between" in help_text
    assert "disconnect: motion, then the device goes away" in help_text
    if driver == "PinchGlove_drv":
        assert "touches: contacts made and broken" in help_text


@pytest.mark.parametrize("rate", ["0", "-1", "nan"])
def test_emulator_rate_zero_is_one_clear_line(cli, rate):
    result = cli("emulate", "Flock_drv", "--rate", rate)
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("gadgetctl: error: emulate Flock_drv: argument --rate: ")
    assert f"must be more than 0 per second, not '{rate}'" in lines[0]


def test_vrpn_emulator_rate_zero_is_one_clear_line(cli):
    result = cli("emulate", "VRPN_drv", "--rate", "0")
    assert result.exit_code == 2
    assert result.stderr.strip().splitlines() == [
        "gadgetctl: error: emulate VRPN_drv: --rate must be more than 0 and at most 100000 "
        "samples per second, not 0 (see 'gadgetctl emulate VRPN_drv --help')"
    ]


@pytest.mark.parametrize("command", ["monitor", "serve"])
def test_rate_zero_of_monitor_and_serve(cli, command):
    result = cli(command, REPO / "examples" / "waveform.jconf", "--rate", "0", "--duration", "0.1")
    assert result.exit_code == 2
    assert result.stderr.strip() == (
        "gadgetctl: error: --rate must be more than 0 and at most 10000 frames per second, not 0"
    )


@pytest.mark.parametrize("command", ["monitor", "serve"])
@pytest.mark.parametrize("duration", ["-1", "nan"])
def test_a_duration_that_is_not_a_length_of_time(cli, command, duration):
    result = cli(command, REPO / "examples" / "waveform.jconf", "--duration", duration)
    assert result.exit_code == 2
    assert result.stderr.strip() == (
        f"gadgetctl: error: --duration is a number of seconds, 0 or more, not {duration}"
    )


# --- /FRAME and RATE over the same window ------------------------------------------------------


def _run(stats: DeviceStats, start: float, seconds: float, sample_rate: float, frame_rate: float):
    """Samples at ``sample_rate`` and frame ends at ``frame_rate`` from ``start``."""
    frames = round(seconds * frame_rate)
    per_frame = sample_rate / frame_rate
    made = 0.0
    for i in range(1, frames + 1):
        t = start + i / frame_rate
        due = round(i * per_frame) - round(made)
        stats.add_timestamps([t - k / sample_rate for k in reversed(range(due))])
        made += due
        stats.end_frame(t)
    return start + seconds


def test_per_frame_covers_the_window_of_the_rate():
    stats = DeviceStats("x", window=1.0)
    t = _run(stats, 0.0, 10.0, 1000.0, 100.0)  # 10 per frame for ten seconds
    t = _run(stats, t, 2.0, 100.0, 100.0)  # then 1 per frame
    snap = stats.snapshot(t)
    assert snap.window_rate == pytest.approx(100.0, rel=0.02)
    assert snap.window_samples_per_frame == pytest.approx(1.0, rel=0.02)
    assert snap.mean_samples_per_frame == pytest.approx(10_200 / 1_200, rel=0.01)  # the whole run
    # RATE / frame rate = /FRAME, both over the last second
    assert snap.window_rate / 100.0 == pytest.approx(snap.window_samples_per_frame, rel=0.03)

    t = _run(stats, t, 2.0, 0.0001, 100.0)  # frames go on, the device went quiet
    snap = stats.snapshot(t)
    assert snap.window_rate == 0.0 and snap.window_samples_per_frame == 0.0
    assert snap.mean_samples_per_frame > 5


def test_per_frame_without_timed_frames_is_the_run_mean():
    from gadgetctl.cli.monitor_text import per_frame_text

    stats = DeviceStats("x")
    stats.add_timestamps([0.1, 0.2, 0.3])
    stats.end_frame()
    snap = stats.snapshot(1.0)
    assert snap.window_samples_per_frame is None
    assert per_frame_text(snap) == "3.00"
    timed = DeviceSnapshot(**{**snap.to_dict(), "window_samples_per_frame": 1.5})
    assert per_frame_text(timed) == "1.50"
    assert per_frame_text(None) == "-"


# --- scaffold ----------------------------------------------------------------------------------


@pytest.mark.parametrize("package", [False, True], ids=["folder", "package"])
def test_scaffold_next_steps_say_how_to_get_pytest(cli, tmp_path, package):
    args = [
        "scaffold",
        "driver",
        "AcmeWand",
        "--type",
        "digital",
        "--transport",
        "udp",
        "--dir",
        tmp_path,
    ]
    result = cli(*args, *(["--package"] if package else []))
    assert result.exit_code == 0, result.stderr
    steps = result.stdout.split("next:", 1)[1].splitlines()
    pytest_step = next(i for i, line in enumerate(steps) if "python -m pytest" in line)
    if package:
        install = next(line for line in steps if "pip install --editable" in line)
        assert "[test]'" in install and "brings pytest" in install
        assert steps.index(install) < pytest_step
    else:
        install = next(i for i, line in enumerate(steps) if "python -m pip install pytest" in line)
        assert install == pytest_step - 1


def test_articles_follow_the_sound_of_the_first_letter():
    from gadgetctl.wording import article, with_article

    assert with_article("alias") == "an alias" and with_article("int") == "an int"
    assert with_article("position_proxy") == "a position_proxy" and article("") == "a"
