"""A command line that names its command registers that command alone (issue 27 goal 4):
the mapping of names to modules must stay true, and such a command line must not import
the other command modules."""

from __future__ import annotations

import pytest
import typer.main

from gadgetctl.cli.app import build_app
from gadgetctl.cli.commands import COMMANDS

from conftest import modules_after_validate


def test_the_full_application_has_every_command_and_no_other():
    group = typer.main.get_command(build_app())
    assert sorted(group.commands) == sorted(COMMANDS)


@pytest.mark.parametrize("name", list(COMMANDS))
def test_each_name_registers_its_own_command_only(name):
    group = typer.main.get_command(build_app(name))
    assert list(group.commands) == [name]
    full = typer.main.get_command(build_app()).commands[name]
    assert [p.name for p in group.commands[name].params] == [p.name for p in full.params]


@pytest.mark.timeout(60)
def test_validate_does_not_import_the_other_commands(tmp_path):
    (tmp_path / "a.jconf").write_text("<configuration/>", encoding="utf-8")
    modules = modules_after_validate(tmp_path)
    assert {m for m in modules if m.endswith("_cmd")} == {"gadgetctl.cli.validate_cmd"}
