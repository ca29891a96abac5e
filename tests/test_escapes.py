"""Names, values and paths from files and recordings reach terminals and line-oriented
formats escaped (issue 13 item 4); JSON keeps the exact strings."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from gadgetctl.safetext import printable

from config_samples import CONFIG_NS

REPO = Path(__file__).resolve().parents[1]
EVIL = "\x1b]0;pwned\x07\x1b[2J\n::error file=x.jconf::forged\x9b31m\u202e"
RAW = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u202e]")  # what no line of output may contain


def _configuration(element_name: str, value: str) -> str:
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
        f'<configuration xmlns="{CONFIG_NS}" name="escapes">\n<elements>\n'
        f'<keyboard_mouse_device name="{element_name}" version="2">'
        f"<mouse_sensitivity>{value}</mouse_sensitivity><bogus_property>1</bogus_property>"
        "</keyboard_mouse_device>\n"
        '<alias name="Alias" version="1"><proxy>Nowhere</proxy></alias>\n'
        "</elements>\n</configuration>\n"
    )


@pytest.fixture
def evil_file(tmp_path) -> Path:
    path = tmp_path / f"odd{EVIL.replace('/', '_')}.jconf"
    # XML attribute and text cannot hold C0 controls other than tab/newline: use character
    # references where XML allows them, raw bytes (C1, bidi) otherwise
    name = "Keys&#10;::error::forged\u0085\u202e"
    path.write_text(_configuration(name, "0.5\u009b2J\u0085\nsecond line"), encoding="utf-8")
    return path


def _assert_clean(text: str) -> None:
    assert not RAW.search(text), [line for line in text.splitlines() if RAW.search(line)][:3]


def test_printable_escapes_controls_and_keeps_other_text():
    assert printable("a\nb\x1b[2J\x85\u202e\tz é ✓") == "a\\nb\\x1b[2J\\x85\\u202e\\tz é ✓"
    assert printable("plain text") == "plain text"


def test_validate_text_and_github_keep_one_record_per_line(cli, evil_file):
    text = cli("validate", evil_file)
    assert text.exit_code == 1
    _assert_clean(text.stdout)
    assert not any(line.startswith("::error") for line in text.stdout.splitlines())
    assert "\\n::error file=x.jconf::forged" in text.stdout
    github = cli("validate", evil_file, "--format", "github")
    _assert_clean(github.stdout)
    lines = github.stdout.splitlines()
    assert lines and all(line.startswith(("::error ", "::warning ", "::notice ")) for line in lines)
    assert sum("forged" in line for line in lines) == len(lines)  # every annotation names the file


def test_validate_json_keeps_exact_strings(cli, evil_file):
    result = cli("validate", evil_file, "--format", "json")
    data = json.loads(result.stdout)
    paths = {d["path"] for d in (data["diagnostics"] if isinstance(data, dict) else data)}
    assert str(evil_file) in paths or any(EVIL in p for p in paths)


def test_config_show_escapes_values_and_names(cli, evil_file):
    result = cli("config", "show", evil_file)
    _assert_clean(result.stdout)
    assert "\\x9b2J\\x85\\nsecond line" in result.stdout
    assert "Keys\\n::error::forged\\x85\\u202e" in result.stdout
    exact = json.loads(cli("config", "show", evil_file, "--format", "json").stdout)
    assert "0.5\u009b2J\u0085\nsecond line" in _strings(exact)


def _strings(data) -> set[str]:
    if isinstance(data, str):
        return {data}
    if isinstance(data, dict):
        data = list(data.values())
    return set().union(*map(_strings, data)) if isinstance(data, list) else set()


@pytest.mark.parametrize("fmt", ["text", "dot", "mermaid"])
def test_config_graph_escapes_labels(cli, evil_file, fmt):
    result = cli("config", "graph", evil_file, "--format", fmt)
    assert result.exit_code == 0, result.stderr
    _assert_clean(result.stdout)
    shown = "Keys\\n::error::forged\\x85\\u202e"
    assert (
        shown.replace("\\", "\\\\") if fmt == "dot" else shown
    ) in result.stdout  # dot doubles backslashes
    if fmt == "mermaid":
        assert all(line.startswith(("flowchart", "  ")) for line in result.stdout.splitlines())


@pytest.fixture
def evil_recording(cli, tmp_path) -> Path:
    recording = tmp_path / "rec.ndjson"
    result = cli(
        "monitor",
        REPO / "examples" / "waveform.jconf",
        "--duration",
        "0.3",
        "--format",
        "table",
        "--record",
        recording,
    )
    assert result.exit_code == 0, result.stderr
    text = recording.read_text().replace("Waveform Sticks", json.dumps(EVIL)[1:-1])
    recording.write_text(text)
    return recording


def test_replay_summary_and_table_escape_device_names(cli, evil_recording):
    summary = cli("replay", evil_recording, "--summary")
    assert summary.exit_code == 0, summary.stderr
    _assert_clean(summary.stdout)
    assert printable(EVIL) in summary.stdout
    table = cli("replay", evil_recording, "--format", "table", "--speed", "100")
    _assert_clean(table.stdout + table.stderr)
    assert printable(EVIL) in table.stdout
    exact = json.loads(cli("replay", evil_recording, "--summary", "--format", "ndjson").stdout)
    assert EVIL in {d["name"] for d in exact["devices"]}


def test_is_printable_says_whether_printable_changes_a_text():
    from gadgetctl.safetext import is_printable, printable

    for text in (
        "plain",
        "",
        "x +0.500 y 1.500 m  rot +0.0°",
        "a\nb",
        "\x1b[2J",
        "r\u202el",
        "\x85",
    ):
        assert is_printable(text) == (printable(text) == text)
