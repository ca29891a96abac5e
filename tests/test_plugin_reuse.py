"""A process that looks for driver plug-ins again and again (validate in-process, the
language server) parses a plug-in's source once while it stays the same and reads the
installed entry points once while sys.path stays the same, and sees every change: a source
that changes, a plug-in that comes or goes, a distribution installed on sys.path."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from gadgetctl.input.plugins.discovery import DriverDirectory, DriverSearch, PluginSource
from gadgetctl.input.plugins.metadata import read_metadata

PLUGINS = Path(__file__).parent / "data" / "plugins"


def _source(element_type: str) -> str:
    return (
        '"""A test plug-in."""\n'
        "GADGETCTL_API_VERSION = 1\n"
        f"ELEMENT_TYPES = {{{element_type!r}: ('digital',)}}\n\n\n"
        "def register(registry):\n"
        "    pass\n"
    )


def _search(directory: Path) -> DriverSearch:
    return DriverSearch([DriverDirectory(directory, PluginSource.OPTION)], entry_points=False)


def _types(directory: Path) -> dict[str, list[str]]:
    return {p.name: sorted(p.metadata.element_types) for p in _search(directory).plugins()}


def test_unchanged_sources_are_parsed_once_and_a_changed_source_again(tmp_path):
    module = tmp_path / "Knob_drv.py"
    module.write_text(_source("knob_a"))
    assert read_metadata(module) is read_metadata(module)  # shared while unchanged
    assert _types(tmp_path) == {"Knob_drv": ["knob_a"]}

    module.write_text(_source("knob_b"))  # the same size
    status = module.stat()
    os.utime(module, ns=(status.st_atime_ns, status.st_mtime_ns + 1_000_000))  # within a tick
    assert _types(tmp_path) == {"Knob_drv": ["knob_b"]}

    package = tmp_path / "Dial_drv"
    package.mkdir()
    (package / "__init__.py").write_text(_source("dial"))
    assert _types(tmp_path) == {"Dial_drv": ["dial"], "Knob_drv": ["knob_b"]}
    (package / "dial.jdef").write_text("<definition/>")
    (dial,) = [p for p in _search(tmp_path).plugins() if p.name == "Dial_drv"]
    assert dial.definition_files == [package / "dial.jdef"]

    module.unlink()
    assert _types(tmp_path) == {"Dial_drv": ["dial"]}
    module.write_text("not python (")
    assert read_metadata(module).problems[0].startswith("syntax error")


def test_a_distribution_installed_on_sys_path_is_seen(tmp_path, monkeypatch):
    site = tmp_path / "site"
    site.mkdir()
    monkeypatch.syspath_prepend(str(site))
    assert DriverSearch([], entry_points=True).find("LateButton_drv") is None

    shutil.copytree(PLUGINS / "Button_drv", site / "late_buttons")
    dist = site / "late_buttons-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: late-buttons\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text("[gadgetctl.drivers]\nLateButton_drv = late_buttons\n")
    info = DriverSearch([], entry_points=True).find("LateButton_drv")
    assert info is not None and info.source is PluginSource.ENTRY_POINT
    assert info.origin == "LateButton_drv = late_buttons (late-buttons 1.0)"

    shutil.rmtree(dist)
    assert DriverSearch([], entry_points=True).find("LateButton_drv") is None
