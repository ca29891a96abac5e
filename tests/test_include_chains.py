"""A long chain of includes loads iteratively (issue 13 item 5): 5,000 files deep gives
a result, never a RecursionError; the time is measured in bench/bench_include_chain.py."""

from __future__ import annotations

from pathlib import Path

import pytest

from config_samples import CONFIG_NS


def write_include_chain(directory: Path, length: int) -> Path:
    """``c0.jconf`` includes ``c1.jconf``, which includes ``c2.jconf``... each with one
    element; returns the first file."""
    for i in range(length):
        include = f"<include>c{i + 1}.jconf</include>\n" if i + 1 < length else ""
        (directory / f"c{i}.jconf").write_text(
            '<?xml version="1.0" encoding="UTF-8"?>\n'
            '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
            f'<configuration xmlns="{CONFIG_NS}" name="c{i}">\n{include}<elements>\n'
            f'<keyboard_mouse_device name="Keys{i}" version="2"/>\n</elements>\n</configuration>\n'
        )
    return directory / "c0.jconf"


@pytest.mark.timeout(300)
def test_a_5000_file_include_chain_validates(cli, tmp_path):
    first = write_include_chain(tmp_path, 5000)
    result = cli("validate", first, "--format", "json")
    assert "internal error" not in result.stderr
    assert result.exit_code == 0, result.stdout[-2000:]


@pytest.mark.timeout(300)
@pytest.mark.parametrize(
    "command", [("config", "show"), ("config", "graph"), ("config", "pending")], ids=" ".join
)
def test_config_commands_follow_a_1000_file_include_chain(cli, tmp_path, command):
    first = write_include_chain(tmp_path, 1000)
    result = cli(*command, first)
    assert "internal error" not in result.stderr
    assert result.exit_code in (0, 1)
    if command == ("config", "show"):
        assert "Keys999" in result.stdout and "Keys0" in result.stdout


def test_include_order_and_cycles_are_kept(cli, tmp_path):
    from gadgetctl.jccl.configload import load_configuration

    first = write_include_chain(tmp_path, 4)
    last = tmp_path / "c3.jconf"
    last.write_text(
        last.read_text().replace("<elements>", "<include>c1.jconf</include>\n<elements>")
    )
    config = load_configuration([first])
    assert [e.name for e in config.loaded] == ["Keys3", "Keys2", "Keys1", "Keys0"]
    cycles = [d for d in config.diagnostics if d.code == "CFG002"]
    assert [d.message for d in cycles] == [
        "include cycle: c1.jconf -> c2.jconf -> c3.jconf -> c1.jconf"
    ]
