"""Plug-in code is imported only from places other users cannot write to, unless accepted
with --trust-driver-path (issue 13 item 9)."""

from __future__ import annotations

import os

import pytest

from gadgetctl.input.plugins.trust import accept_writable_places


@pytest.fixture(autouse=True)
def _reset_trust():
    yield
    accept_writable_places(False)  # the option sets it for the process


@pytest.fixture
def plugin_dir(cli, tmp_path):
    result = cli(
        "scaffold", "driver", "Gizmo", "--transport", "none", "--dir", tmp_path / "drivers"
    )
    assert result.exit_code == 0, result.stderr
    return tmp_path / "drivers"


def _example(plugin_dir):
    return plugin_dir / "Gizmo_drv" / "example.jconf"


@pytest.mark.parametrize("command", [("config", "pending"), ("doctor",)], ids=" ".join)
def test_a_world_writable_driver_path_is_refused_with_the_directory_named(cli, plugin_dir, command):
    plugin_dir.chmod(0o777)
    result = cli(*command, _example(plugin_dir))
    assert result.exit_code == 1
    assert f"not imported: {plugin_dir} can be written by other users" in result.stdout
    assert "--trust-driver-path" in result.stdout


def test_monitor_and_drivers_load_refuse_it_too(cli, plugin_dir):
    plugin_dir.chmod(0o777)
    monitor = cli("monitor", _example(plugin_dir), "--duration", "0.2", "--format", "table")
    assert monitor.exit_code == 1 and "can be written by other users" in monitor.stderr
    load = cli("drivers", "load", "--driver-path", plugin_dir, "Gizmo_drv")
    assert load.exit_code == 1 and "DRV011" in load.stdout


def test_a_plugin_file_owned_by_another_user_is_refused(cli, plugin_dir):
    wrapper = plugin_dir / "Gizmo_drv" / "wrapper.py"
    os.chown(wrapper, 1234, 1234)
    result = cli("config", "pending", _example(plugin_dir))
    assert result.exit_code == 1 and f"{wrapper} can be written by other users" in result.stdout


def test_trust_driver_path_accepts_it_and_a_private_directory_needs_nothing(cli, plugin_dir):
    plugin_dir.chmod(0o777)
    trusted = cli("config", "pending", _example(plugin_dir), "--trust-driver-path")
    assert trusted.exit_code == 0, trusted.stdout
    accept_writable_places(False)
    plugin_dir.chmod(0o755)
    private = cli("config", "pending", _example(plugin_dir))
    assert private.exit_code == 0, private.stdout
