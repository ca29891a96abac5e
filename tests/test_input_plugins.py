"""Driver plug-ins: discovery without importing, loading with version, definition and
device-type checks, private module names, entry points, and the `drivers` commands."""

import json
import shutil
import sys
import textwrap
from pathlib import Path

import pytest
from typer.testing import CliRunner

from gadgetctl.cli.app import build_app
from gadgetctl.input import PLUGIN_API_VERSION
from gadgetctl.input.definitions import driver_definition_dirs
from gadgetctl.input.plugins.discovery import (
    DriverDirectory,
    DriverSearch,
    PluginSource,
    standard_directories,
)
from gadgetctl.input.plugins.loader import PluginLoader
from gadgetctl.input.plugins.metadata import parse_metadata
from gadgetctl.input.registry import DeviceRegistry
from gadgetctl.jccl.repository import default_repository

CORPUS_DEFINITIONS = Path("/work/shared/corpus/vrjuggler/modules/vrjuggler/data/definitions")
PLUGINS = Path(__file__).parent / "data" / "plugins"
TEST_PLUGINS = {"Button_drv", "BrokenImport_drv", "WrongApi_drv", "Mismatch_drv"}


@pytest.fixture
def repo():
    return default_repository([CORPUS_DEFINITIONS] if CORPUS_DEFINITIONS.is_dir() else [])


def search_in(*directories):
    return DriverSearch(
        [DriverDirectory(Path(d), PluginSource.OPTION) for d in directories], entry_points=False
    )


def imported_from(directory: Path, before: set[str]) -> list[str]:
    """Modules from ``directory`` imported since ``before`` was taken (a copy of sys.modules' keys)."""
    root = str(directory.resolve())
    return [
        name
        for name, module in list(sys.modules.items())
        if name not in before and (getattr(module, "__file__", None) or "").startswith(root)
    ]


def test_listing_finds_every_plugin_without_importing_any():
    before = set(sys.modules)
    plugins = {p.name: p for p in search_in(PLUGINS).plugins()}
    assert set(plugins) == TEST_PLUGINS
    assert plugins["WrongApi_drv"].metadata.api_version == 99
    assert plugins["BrokenImport_drv"].metadata.element_types == {"broken_device": ("digital",)}
    assert plugins["Button_drv"].package and plugins["Button_drv"].definition_files
    assert not plugins["BrokenImport_drv"].package
    assert imported_from(PLUGINS, before) == []


def test_loading_reports_each_failure_precisely_and_loads_the_rest(repo):
    registry = DeviceRegistry.with_builtins()
    loader = PluginLoader(registry, repo)
    search = search_in(PLUGINS)
    results = {name: loader.load_name(name, search) for name in sorted(TEST_PLUGINS)}

    assert results["Button_drv"].ok
    assert registry.get("button_device").device_class.__name__ == "ButtonDevice"
    assert "button_device" in repo  # the plug-in's own definition joined the repository

    broken = results["BrokenImport_drv"]
    assert not broken.ok and broken.diagnostics[0].code == "DRV003"
    assert broken.reason == "import failed: RuntimeError: BrokenImport_drv was imported"
    assert (
        broken.diagnostics[0].path.endswith("BrokenImport_drv.py")
        and broken.diagnostics[0].line == 7
    )

    wrong = results["WrongApi_drv"]
    assert not wrong.ok and wrong.diagnostics[0].code == "DRV002"
    assert f"version 99, but this gadgetctl provides version {PLUGIN_API_VERSION}" in wrong.reason

    mismatch = results["Mismatch_drv"]
    assert not mismatch.ok and [d.code for d in mismatch.diagnostics] == ["DRV006", "DRV006"]
    messages = " ".join(d.message for d in mismatch.diagnostics)
    assert "provides analog data but mismatch_device does not derive from analog_device" in messages
    assert "derives from digital_device but the class provides no digital data" in messages
    assert registry.get("mismatch_device") is None  # nothing of a failed plug-in is registered

    assert not any(
        m.startswith(("Button_drv", "wrapper")) for m in sys.modules
    )  # private names only


def test_plugins_with_the_same_module_names_do_not_meet(repo, tmp_path):
    for name, token in (("Alpha_drv", "alpha_device"), ("Beta_drv", "beta_device")):
        package = tmp_path / name
        package.mkdir()
        (package / "__init__.py").write_text(
            textwrap.dedent(f"""
            GADGETCTL_API_VERSION = 1
            ELEMENT_TYPES = {{"{token}": ("digital",)}}

            def register(registry):
                from .wrapper import Device
                registry.register_device(Device)
            """)
        )
        (package / "wrapper.py").write_text(
            textwrap.dedent(f"""
            from gadgetctl.input import Digital

            class Device(Digital):
                ELEMENT_TYPE = "{token}"
            """)
        )
        (package / f"{token}.jdef").write_text(
            (PLUGINS / "Button_drv" / "button_device.jdef")
            .read_text()
            .replace("button_device", token)
        )
    registry = DeviceRegistry()
    loader = PluginLoader(registry, repo)
    search = search_in(tmp_path)
    assert loader.load_name("Alpha_drv", search).ok
    assert loader.load_name("Beta_drv", search).ok
    alpha, beta = (
        registry.get("alpha_device").device_class,
        registry.get("beta_device").device_class,
    )
    assert alpha is not beta and alpha.__module__ != beta.__module__
    assert "wrapper" not in sys.modules


def test_a_plugin_loaded_twice_registers_once(repo):
    registry = DeviceRegistry()
    loader = PluginLoader(registry, repo)
    search = search_in(PLUGINS)
    first = loader.load_name("Button_drv", search)
    assert loader.load_name("Button_drv", search) is first


def test_a_second_plugin_for_the_same_type_is_ignored_with_a_warning(repo, tmp_path):
    shutil.copytree(PLUGINS / "Button_drv", tmp_path / "Button2_drv")
    registry = DeviceRegistry()
    loader = PluginLoader(registry, repo)
    search = search_in(PLUGINS, tmp_path)
    assert loader.load_name("Button_drv", search).ok
    second = loader.load_name("Button2_drv", search)
    assert second.ok and [d.code for d in second.diagnostics] == ["DRV009"]
    assert registry.get("button_device").plugin == "Button_drv"


def test_metadata_problems_are_listed():
    meta = parse_metadata(
        "VERSION = 1\nGADGETCTL_API_VERSION = compute()\nELEMENT_TYPES = {'x': ('digital', 'sound')}\n"
    )
    problems = " ".join(meta.problems)
    assert "GADGETCTL_API_VERSION is not a literal" in problems
    assert "unknown device type 'sound'" in problems
    assert "no register(registry) function" in problems
    assert parse_metadata("def broken(:\n").problems[0].startswith("syntax error at line 1")


def test_search_places_in_order(tmp_path):
    env = {"GADGETCTL_DRIVER_PATH": f"{tmp_path / 'a'}{__import__('os').pathsep}{tmp_path / 'b'}"}
    directories = standard_directories([tmp_path / "c"], environ=env)
    assert [d.source for d in directories] == [
        PluginSource.BUNDLED,
        PluginSource.ENVIRONMENT,
        PluginSource.ENVIRONMENT,
        PluginSource.OPTION,
    ]
    assert [d.path.name for d in directories[1:]] == ["a", "b", "c"]


def test_an_earlier_place_shadows_a_later_plugin_of_the_same_name(tmp_path):
    shutil.copytree(PLUGINS / "Button_drv", tmp_path / "Button_drv")
    search = search_in(PLUGINS, tmp_path)
    found = [p for p in search.plugins() if p.name == "Button_drv"]
    assert len(found) == 2 and found[1].shadowed_by is found[0]
    assert search.find("Button_drv").path == PLUGINS / "Button_drv"


def test_definition_directories_of_plugins():
    dirs = driver_definition_dirs([PLUGINS], bundled=False, environ={})
    assert {d.name for d in dirs} == {"Button_drv", "Mismatch_drv"}


def test_installed_plugins_come_from_entry_points(tmp_path, monkeypatch, repo):
    site = tmp_path / "site"
    (site / "gadget_extra").mkdir(parents=True)
    (site / "gadget_extra" / "__init__.py").write_text("")
    shutil.copytree(PLUGINS / "Button_drv", site / "gadget_extra" / "buttons")
    dist = site / "gadget_extra-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: gadget-extra\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text(
        "[gadgetctl.drivers]\nExtraButton_drv = gadget_extra.buttons\n"
    )
    monkeypatch.syspath_prepend(str(site))
    search = DriverSearch([], entry_points=True)
    info = search.find("ExtraButton_drv")
    assert info is not None and info.source is PluginSource.ENTRY_POINT
    assert info.path == site / "gadget_extra" / "buttons" and info.module == "gadget_extra.buttons"
    assert "gadget_extra" not in sys.modules  # found without importing
    result = PluginLoader(DeviceRegistry(), repo).load(info)
    assert result.ok and result.registrations[0].element_type == "button_device"
    for name in [m for m in sys.modules if m.startswith("gadget_extra")]:
        del sys.modules[name]


# -- commands -----------------------------------------------------------------------------


def run(*args):
    return CliRunner().invoke(build_app(), list(args))


def test_drivers_list_shows_every_plugin_and_its_problems():
    before = set(sys.modules)
    result = run("drivers", "list", "--driver-path", str(PLUGINS))
    assert result.exit_code == 0, result.output
    for name in TEST_PLUGINS:
        assert name in result.output
    assert "written for plug-in API 99; gadgetctl provides 1" in result.output
    assert "button_device: digital" in result.output
    assert imported_from(PLUGINS, before) == []
    data = json.loads(
        run("drivers", "list", "--driver-path", str(PLUGINS), "--format", "json").output
    )
    by_name = {p["name"]: p for p in data["plugins"]}
    assert set(by_name) >= TEST_PLUGINS and by_name["WrongApi_drv"]["api_version"] == 99
    assert by_name["Button_drv"]["provides"] == {"button_device": ["digital"]}


def test_drivers_load_reports_failures_loads_the_rest_and_exits_1():
    result = run(
        "drivers",
        "load",
        "Button_drv",
        "BrokenImport_drv",
        "WrongApi_drv",
        "--driver-path",
        str(PLUGINS),
    )
    assert result.exit_code == 1
    assert "Button_drv: ok: button_device -> ButtonDevice (digital)" in result.output
    assert (
        "BrokenImport_drv: failed: import failed: RuntimeError: BrokenImport_drv was imported"
        in result.output
    )
    assert "WrongApi_drv: failed: written for plug-in API version 99" in result.output
    assert "1 loaded, 2 failed" in result.output
    data = json.loads(
        run("drivers", "load", "Button_drv", "--driver-path", str(PLUGINS), "-f", "json").output
    )
    assert (
        data["failed"] == 0
        and data["plugins"][0]["registered"][0]["element_type"] == "button_device"
    )


def test_drivers_load_accepts_a_path():
    result = run("drivers", "load", str(PLUGINS / "Button_drv"))
    assert result.exit_code == 0, result.output


def test_drivers_list_includes_the_driver_path_of_a_configuration(tmp_path):
    config = tmp_path / "drivers.jconf"
    config.write_text(f"""<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="d"><elements>
  <input_manager name="IM" version="2"><driver_path>{PLUGINS}</driver_path></input_manager>
</elements></configuration>
""")
    data = json.loads(run("drivers", "list", "--config", str(config), "-f", "json").output)
    sources = {p["name"]: p["source"] for p in data["plugins"]}
    assert sources["Button_drv"] == "driver_path" and sources["LinuxJoydev_drv"] == "bundled"
