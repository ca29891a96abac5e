"""Installed entry points are read without importlib.metadata when no distribution on
sys.path mentions the group (issue 27 goal 4), and through it whenever one might."""

from __future__ import annotations

import sys
import zipfile

from gadgetctl.input.plugins import discovery
from gadgetctl.input.plugins.distscan import may_declare

from conftest import modules_after_validate

GROUP = "gadgetctl.drivers"


def _dist(site, name: str, entry_points: str | None) -> None:
    folder = site / f"{name}-1.0.dist-info"
    folder.mkdir(parents=True)
    (folder / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 1.0\n")
    if entry_points is not None:
        (folder / "entry_points.txt").write_text(entry_points)


def test_no_distribution_declaring_the_group(tmp_path):
    _dist(tmp_path, "plain", None)
    _dist(tmp_path, "tool", "[console_scripts]\ntool = tool.main:run\n")
    (tmp_path / "odd.egg-info").write_text("Metadata-Version: 1.0\n")  # a PKG-INFO file
    assert not may_declare(GROUP, [str(tmp_path), str(tmp_path / "missing")])


def test_a_distribution_declaring_the_group(tmp_path):
    _dist(tmp_path, "tool", "[console_scripts]\ntool = tool.main:run\n")
    _dist(tmp_path, "buttons", f"[ {GROUP} ]\nButton_drv = buttons\n")
    assert may_declare(GROUP, [str(tmp_path)])
    egg = tmp_path / "eggs" / "old.egg-info"
    egg.mkdir(parents=True)
    (egg / "entry_points.txt").write_text(f"[{GROUP}]\nOld_drv = old\n")
    assert may_declare(GROUP, [str(tmp_path / "eggs")])


def test_places_only_importlib_metadata_reads_are_left_to_it(tmp_path, monkeypatch):
    archive = tmp_path / "bundle.zip"
    with zipfile.ZipFile(archive, "w") as z:
        z.writestr("x.py", "")
    assert may_declare(GROUP, [str(archive)])
    assert may_declare(GROUP, [str(tmp_path / "thing.egg")])

    class Finder:
        @staticmethod
        def find_distributions(context=None):
            return iter(())

    monkeypatch.setattr(sys, "meta_path", [*sys.meta_path, Finder])
    assert may_declare(GROUP, [])


def test_discovery_agrees_with_importlib_metadata(tmp_path, monkeypatch):
    site = tmp_path / "site"
    _dist(site, "tool", "[console_scripts]\ntool = tool.main:run\n")
    monkeypatch.syspath_prepend(str(site))
    discovery._ENTRY_POINTS.clear()
    assert discovery._installed_entry_points() == []
    _dist(site, "buttons", f"[{GROUP}]\nLate_drv = late_buttons\n")
    assert discovery._installed_entry_points() == [("Late_drv", "late_buttons", "buttons 1.0")]


def test_validate_does_not_import_importlib_metadata(tmp_path):
    (tmp_path / "a.jconf").write_text("<configuration/>", encoding="utf-8")
    modules = modules_after_validate(tmp_path)
    assert "gadgetctl.input.plugins.discovery" in modules  # (discovery ran)
    assert not {"importlib.metadata", "email"} & modules
