"""Ordinary mistakes get one correct line and exit status 2 (issue 12 item 6): a directory
where a file belongs, a mistyped path or name (with "did you mean"), a recording to
standard output, a check that would check nothing."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO, write

WAVEFORM = REPO / "examples" / "waveform.jconf"


def gadgetctl(
    *args: str | Path, cwd: Path = REPO, timeout: float = 60
) -> subprocess.CompletedProcess:
    env = {**os.environ, "NO_COLOR": "1"}
    env.pop("GADGETCTL_DEBUG", None)
    return subprocess.run(
        [sys.executable, "-m", "gadgetctl", *map(str, args)],
        cwd=cwd,
        capture_output=True,
        timeout=timeout,
        env=env,
        stdin=subprocess.DEVNULL,
    )


def one_line_error(stderr: str | bytes) -> str:
    """The single error line (nothing else on stderr, no traceback, no internal error)."""
    text = stderr.decode() if isinstance(stderr, bytes) else stderr
    lines = text.strip().splitlines()
    assert len(lines) == 1, text
    assert lines[0].startswith("gadgetctl: error: ") and "internal error" not in lines[0], text
    return lines[0]


# -- the shared suggestion helper ------------------------------------------------------


def test_suggestions_ignore_case_and_keep_the_spelling():
    from gadgetctl.suggest import close_names, did_you_mean, with_suggestion

    names = ["Waveform Sticks", "Waveform Tracker", "Head Proxy"]
    assert close_names("waveform stick", names)[0] == "Waveform Sticks"
    assert did_you_mean("head proxi", names) == "did you mean 'Head Proxy'?"
    assert (
        did_you_mean("dtrak", ["dtrack", "fastrak", "dtk"], quote=str)
        == "did you mean dtrack, dtk or fastrak?"
    )
    assert did_you_mean("zzzz", names) is None
    assert with_suggestion("no such thing 'zzzz'", "zzzz", names) == "no such thing 'zzzz'"


# -- a directory where a file belongs -----------------------------------------------------


@pytest.mark.timeout(60)
def test_upgrade_output_into_a_directory_is_a_usage_error(cli, tmp_path):
    result = cli("upgrade", WAVEFORM, "-o", tmp_path)
    assert result.exit_code == 2
    line = one_line_error(result.stderr)
    assert (
        f"--output {tmp_path}: is a directory" in line and f"{tmp_path / 'waveform.jconf'}" in line
    )
    assert list(tmp_path.iterdir()) == []
    result = cli("upgrade", WAVEFORM, "-o", tmp_path / "missing" / "out.jconf")
    assert result.exit_code == 2 and "no such directory" in one_line_error(result.stderr)


@pytest.mark.timeout(60)
def test_record_into_a_directory_says_so_once(tmp_path):
    result = gadgetctl(
        "monitor", WAVEFORM, "--duration", "0.2", "--format", "table", "--record", tmp_path
    )
    assert result.returncode == 2
    line = one_line_error(result.stderr)
    assert "is a directory" in line and "exists" not in line


@pytest.mark.timeout(60)
def test_config_show_of_a_directory_says_it_is_a_directory(cli):
    result = cli("config", "show", REPO / "examples")
    assert result.exit_code == 2
    assert "is a directory" in one_line_error(result.stderr)


@pytest.mark.parametrize(
    "command", [("config", "pending"), ("doctor",), ("drivers", "list", "--config")]
)
def test_other_commands_taking_a_configuration_say_it_is_a_directory(cli, command):
    result = cli(*command, REPO / "examples")
    assert result.exit_code == 2
    assert "is a directory" in one_line_error(result.stderr)


# -- monitor's configuration argument -------------------------------------------------------


@pytest.mark.timeout(60)
def test_monitor_on_a_mistyped_path_names_it_and_the_file_meant(cli):
    result = cli("monitor", "examples/waveform.jcon", "--duration", "0.2", cwd=REPO)
    assert result.exit_code == 2
    line = one_line_error(result.stderr)
    assert "examples/waveform.jcon: no such configuration file" in line
    assert "did you mean examples/waveform.jconf?" in line
    result = cli("monitor", "examples/wavefrom.jconf", "--duration", "0.2", cwd=REPO)
    assert "did you mean examples/waveform.jconf?" in one_line_error(result.stderr)


@pytest.mark.timeout(60)
def test_monitor_on_a_directory_says_it_is_a_directory(cli):
    for argument in ("examples", "examples/"):
        result = cli("monitor", argument, "--duration", "0.2", cwd=REPO)
        assert result.exit_code == 2
        assert "examples" in (line := one_line_error(result.stderr)) and "is a directory" in line


# -- --record - ------------------------------------------------------------------------


@pytest.mark.timeout(90)
def test_record_dash_writes_the_recording_to_stdout_and_the_table_to_stderr(tmp_path):
    result = gadgetctl(
        "monitor",
        WAVEFORM,
        "--duration",
        "1",
        "--format",
        "table",
        "--stats",
        "--record",
        "-",
        cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr
    assert not (tmp_path / "-").exists()
    lines = result.stdout.decode().splitlines()
    records = [json.loads(line) for line in lines]  # nothing but records on stdout
    assert records[0]["type"] == "header" and records[-1]["type"] == "end"
    samples = [r for r in records if r["type"] == "sample"]
    assert {r["device"] for r in samples} >= {
        "Waveform Sticks",
        "Waveform Tracker",
        "Waveform Noise",
    }
    assert records[-1]["samples"] == len(samples)
    assert (
        "Waveform Sticks" in result.stderr.decode() and "NAME" in result.stderr.decode()
    )  # the table


@pytest.mark.timeout(60)
def test_record_dash_and_ndjson_would_both_write_stdout(tmp_path):
    result = gadgetctl(
        "monitor",
        WAVEFORM,
        "--duration",
        "0.2",
        "--format",
        "ndjson",
        "--record",
        "-",
        cwd=tmp_path,
    )
    assert result.returncode == 2 and result.stdout == b""
    assert "standard output" in one_line_error(result.stderr)


# -- replay --map ------------------------------------------------------------------------


@pytest.fixture(scope="module")
def recorded(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("rec") / "waveform.ndjson"
    result = gadgetctl(
        "monitor", WAVEFORM, "--duration", "0.5", "--format", "table", "--record", path
    )
    assert result.returncode == 0, result.stderr
    return path


@pytest.mark.timeout(60)
def test_replay_map_of_a_device_not_recorded_is_a_usage_error_with_a_suggestion(recorded):
    result = gadgetctl("replay", recorded, "--map", "Waveform Stick=Lab Stick", "--format", "table")
    assert result.returncode == 2 and result.stdout == b""
    line = one_line_error(result.stderr)
    assert "'Waveform Stick' is not a device of the recording" in line
    assert "did you mean 'Waveform Sticks'" in line


@pytest.mark.timeout(60)
def test_replay_map_to_a_name_the_configuration_lacks_stops_before_its_devices_open(
    recorded, tmp_path
):
    # The configuration's own device is a FIFO-fed joystick: had the replay gone on, the
    # input manager would have configured and started it in place of the replayed one.
    fifo = tmp_path / "js0"
    os.mkfifo(fifo)
    config = write(
        tmp_path / "lab.jconf",
        f"""<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="lab">
  <elements>
    <input_manager name="Input Manager" version="2"><driver>LinuxJoydev_drv</driver></input_manager>
    <linux_joydev name="Lab Stick" version="1"><port_name>{fifo}</port_name></linux_joydev>
  </elements>
</configuration>
""",
    )
    result = gadgetctl(
        "replay",
        recorded,
        "--config",
        config,
        "--map",
        "Waveform Sticks=Lab Stik",
        "--format",
        "table",
    )
    assert result.returncode == 2 and result.stdout == b""
    line = one_line_error(result.stderr)
    assert "'Lab Stik' is not an element of the configuration (did you mean 'Lab Stick'?)" in line


# -- names ----------------------------------------------------------------------------------


@pytest.mark.timeout(60)
def test_monitor_suggests_the_name_meant(cli):
    result = cli("monitor", WAVEFORM, "Waveform_Stick", "--duration", "0.2", "--format", "table")
    assert result.exit_code == 2
    assert (
        "no device, proxy or alias matches 'Waveform_Stick' (did you mean 'Waveform Sticks'"
        in one_line_error(result.stderr)
    )


def test_drivers_load_of_an_unknown_name_is_a_usage_error_with_a_suggestion(cli):
    result = cli("drivers", "load", "DTrack", "DTrack_drv")
    assert result.exit_code == 2 and result.stdout == ""  # nothing was loaded
    assert "no driver plug-in named 'DTrack' (did you mean 'DTrack_drv'" in one_line_error(
        result.stderr
    )


def test_config_show_element_suggests_the_name_meant(cli):
    result = cli("config", "show", WAVEFORM, "--element", "Waveform Stick")
    assert result.exit_code == 2
    assert (
        "no element named 'Waveform Stick' in the configuration (did you mean 'Waveform Sticks'"
        in one_line_error(result.stderr)
    )


def test_defs_show_tree_and_list_base_suggest_the_definition_meant(cli):
    for args in (
        ("defs", "show", "dtrak"),
        ("defs", "tree", "dtrak"),
        ("defs", "list", "--base", "dtrak"),
    ):
        result = cli(*args)
        assert result.exit_code == 2, args
        assert (
            "'dtrak'" in (line := one_line_error(result.stderr)) and "did you mean dtrack" in line
        )


def test_defs_list_of_an_unknown_base_or_category_is_a_usage_error(cli):
    assert cli("defs", "list", "--base", "nosuch").exit_code == 2
    result = cli("defs", "list", "--category", "/Devics")
    assert result.exit_code == 2 and "did you mean /Devices" in one_line_error(result.stderr)
    assert cli("defs", "list", "--category", "/Devices").exit_code == 0


def test_explain_suggests_the_code_meant(cli):
    result = cli("explain", "xml02")
    assert result.exit_code == 2 and "XML002" in one_line_error(result.stderr)


def test_emulate_suggests_the_driver_meant(cli):
    result = cli("emulate", "dtrak")
    # the closest name first; other bundled drivers as close (Fastrak_drv) may follow
    assert result.exit_code == 2 and "did you mean DTrack_drv" in one_line_error(result.stderr)


def test_a_configuration_naming_a_mistyped_driver_gets_a_suggestion(tmp_path):
    from gadgetctl.input.manager import InputManager, ManagerOptions

    config = write(
        tmp_path / "typo.jconf",
        """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="t">
  <elements>
    <input_manager name="Input Manager" version="2"><driver>DTrak_drv</driver></input_manager>
  </elements>
</configuration>
""",
    )
    manager, configuration = InputManager.from_files(
        [config], options=ManagerOptions(start_devices=False)
    )
    with manager:
        manager.configure(configuration)
        (found,) = [d for d in manager.diagnostics if d.code == "DRV001"]
    assert found.hint.startswith("Did you mean 'DTrack_drv'")  # the closest first


# -- a check that checks nothing -----------------------------------------------------------


@pytest.mark.parametrize("fmt", ["text", "json", "sarif"])
def test_validate_on_a_directory_without_jccl_files_is_a_usage_error(cli, tmp_path, fmt):
    write(tmp_path / "notes.txt", "nothing to see")
    write(tmp_path / ".hidden" / "skipped.jconf", "<configuration/>")
    result = cli("validate", tmp_path, "--format", fmt)
    assert result.exit_code == 2 and result.stdout == ""
    line = one_line_error(result.stderr)
    assert (
        str(tmp_path) in line and "no .jconf or .jdef files" in line and "nothing to check" in line
    )


def test_upgrade_on_a_directory_without_jccl_files_is_a_usage_error(cli, tmp_path):
    result = cli("upgrade", "--check", tmp_path)
    assert result.exit_code == 2 and "nothing to check" in one_line_error(result.stderr)


@pytest.mark.timeout(60)
def test_serve_record_dash_is_refused_rather_than_writing_a_file_named_dash(cli, tmp_path):
    result = cli("serve", WAVEFORM, "--record", "-", "--duration", "0.2", cwd=tmp_path)
    assert result.exit_code == 2 and "--record -" in one_line_error(result.stderr)
    assert not (tmp_path / "-").exists()


@pytest.mark.timeout(60)
def test_record_into_a_missing_directory_names_the_option_and_the_directory(tmp_path):
    target = tmp_path / "missing" / "run.ndjson"
    result = gadgetctl(
        "monitor", WAVEFORM, "--duration", "0.2", "--format", "table", "--record", target
    )
    assert result.returncode == 2
    assert f"--record {target}: no such directory {target.parent}" in one_line_error(result.stderr)


def test_validate_on_a_mistyped_path_suggests_the_file_meant(cli):
    result = cli("validate", "examples/wavefrom.jconf", cwd=REPO)
    assert result.exit_code == 2
    assert "did you mean examples/waveform.jconf?" in one_line_error(result.stderr)
