"""Odd but reachable input ends in a diagnostic, never an internal error (issue 13 item 5)."""

from __future__ import annotations

from pathlib import Path

import pytest

from config_samples import CONFIG_NS

REPO = Path(__file__).resolve().parents[1]
CONFIG_COMMANDS = (("validate",), ("config", "show"), ("config", "graph"), ("upgrade", "--check"))
LONG = "a" * 300  # one path component over the 255-byte limit of Linux file systems


def _configuration(
    body: str = "", declaration: str = '<?xml version="1.0" encoding="UTF-8"?>'
) -> str:
    return (
        f'{declaration}\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
        f'<configuration xmlns="{CONFIG_NS}" name="odd">\n{body}<elements/>\n</configuration>\n'
    )


@pytest.mark.parametrize("encoding", ["UTN-8", "EBCDIC-US", "rot13", "base64", "zlib", "punycode"])
@pytest.mark.parametrize(
    "command", (*CONFIG_COMMANDS, ("monitor", "--duration", "0.1")), ids=" ".join
)
def test_unknown_or_non_text_encodings_are_xml_diagnostics(cli, tmp_path, encoding, command):
    path = tmp_path / "odd.jconf"
    path.write_text(_configuration(declaration=f'<?xml version="1.0" encoding="{encoding}"?>'))
    result = cli(*command, path)
    assert "internal error" not in result.stderr
    if command == ("validate",):
        assert result.exit_code == 1
        assert f"odd.jconf:1:31: error XML002 unknown encoding {encoding!r}" in result.stdout


@pytest.mark.parametrize("command", CONFIG_COMMANDS, ids=" ".join)
def test_one_bit_flipped_in_xmlns(cli, tmp_path, command):
    path = tmp_path / "flip.jconf"
    path.write_bytes(_configuration().encode().replace(b"xmlns=", b"xml\xees="))
    result = cli(*command, path)
    assert "internal error" not in result.stderr
    if command == ("validate",):
        assert result.exit_code == 1 and "XML002" in result.stdout and "XML012" in result.stdout


@pytest.mark.parametrize(
    "command", (*CONFIG_COMMANDS, ("config", "pending"), ("doctor",)), ids=" ".join
)
def test_path_components_over_255_bytes(cli, tmp_path, command, monkeypatch):
    body = (
        f"<include>{LONG}.jconf</include>\n<definition_path><dir>{LONG}</dir></definition_path>\n"
    )
    text = _configuration(body).replace(
        "<elements/>",
        f'<elements><input_manager name="IM" version="2"><driver>Foo_drv</driver>'
        f"<driver_path>{LONG}</driver_path></input_manager></elements>",
    )
    path = tmp_path / "long.jconf"
    path.write_text(text)
    monkeypatch.setenv("JCCL_DEFINITION_PATH", str(tmp_path / LONG))
    monkeypatch.setenv("GADGETCTL_DRIVER_PATH", str(tmp_path / LONG))
    result = cli(*command, path)
    assert "internal error" not in result.stderr
    if command == ("validate",):
        assert result.exit_code == 1 and "CFG001" in result.stdout


@pytest.mark.timeout(120)
def test_a_recording_line_nested_100000_deep_is_skipped(cli, tmp_path):
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
    lines = recording.read_text().splitlines(keepends=True)
    lines.insert(2, "[" * 100_000 + "]" * 100_000 + "\n")
    recording.write_text("".join(lines))
    for mode in (
        ("--summary",),
        ("--speed", "100", "--format", "ndjson"),
        ("--speed", "100", "--format", "table"),
    ):
        result = cli("replay", recording, *mode)
        assert "internal error" not in result.stderr, mode
        assert result.exit_code in (0, 1), (mode, result.stderr)
        assert "line 3" in result.stdout + result.stderr, mode
