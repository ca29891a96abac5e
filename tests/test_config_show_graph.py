"""`gadgetctl config show` and `gadgetctl config graph` (issue 4, items 3 and 4)."""

from __future__ import annotations

import json
import subprocess

import pytest

from gadgetctl.input.plugins.catalog import bundled_plugins, plugin_for_type
from gadgetctl.input.plugins.metadata import read_metadata
from gadgetctl.resources import drivers_dir

from config_samples import configuration, write_definitions
from conftest import CORPUS_CONFIGS, CORPUS_DEFINITIONS, require_tool, write

ELEMENTS = """      <input_manager name="Inputs" version="2">
         <driver>DTrack_drv</driver>
      </input_manager>
      <alias name="VJHead" version="1"><proxy>Head</proxy></alias>
      <position_proxy name="Head" version="1"><device>Tracker</device></position_proxy>
      <tracker name="Tracker" version="1">
         <baud>Fast</baud>
         <offset>0.5</offset>
         <units>0.3048</units>
         <position_filters><position_transform_filter name="Scale" version="1"/></position_filters>
         <colour>blue</colour>
      </tracker>
      <position_proxy name="Lost" version="1"><device>Nowhere</device></position_proxy>
"""


@pytest.fixture
def setup(tmp_path):
    definitions = write_definitions(tmp_path / "defs")
    path = write(tmp_path / "c.jconf", configuration(ELEMENTS))
    return path, ("--no-bundled", "-d", definitions)


def test_show_json_has_every_effective_property_with_its_source(cli, setup):
    path, options = setup
    result = cli("config", "show", path, "--element", "Tracker", "--format", "json", *options)
    assert result.exit_code == 0
    (tracker,) = json.loads(result.stdout)
    props = {p["name"]: p for p in tracker["properties"]}
    assert props["baud"]["values"] == [
        {"source": "written", "value": "9600", "written": "Fast", "label": "Fast"}
    ]
    assert [v["source"] for v in props["offset"]["values"]] == ["written", "default", "default"]
    assert [v["value"] for v in props["offset"]["values"]] == ["0.5", "0.0", "1.5"]
    assert props["units"]["values"][0] == {"source": "written", "value": "0.3048", "label": "Feet"}
    assert props["port"]["values"] == [{"source": "default", "value": "/dev/ttyS0"}]
    assert props["position_filters"]["inherited_from"] == "positional_device"
    assert (
        props["position_filters"]["values"][0]["element"]["full_name"]
        == "Tracker/position_filters/Scale"
    )
    assert props["colour"]["known"] is False


def test_show_text(cli, setup):
    path, options = setup
    result = cli("config", "show", path, *options)
    assert result.exit_code == 0
    assert "tracker 'Tracker' (version 1)" in result.stdout
    assert "Fast = 9600" in result.stdout and "0.3048 (Feet)" in result.stdout
    assert "0.5, 0.0 (default), 1.5 (default)" in result.stdout
    assert "[from positional_device]" in result.stdout
    assert "position_transform_filter 'Scale'" in result.stdout
    assert "\x1b[" not in result.stdout  # no colour when not on a terminal


def test_show_unknown_element_is_a_usage_error(cli, setup):
    path, options = setup
    result = cli("config", "show", path, "--element", "Nobody", *options)
    assert result.exit_code == 2 and "Nobody" in result.stderr


def test_graph_text_tree(cli, setup):
    path, options = setup
    result = cli("config", "graph", path, *options)
    assert result.exit_code == 0
    lines = result.stdout.splitlines()
    assert lines[0] == "alias 'VJHead'"
    assert lines[1] == "└── proxy → position_proxy 'Head'"
    assert (
        lines[2]
        == "    └── device → tracker 'Tracker'  [no known driver plug-in handles this type]"
    )
    assert "missing 'Nowhere'" in result.stdout
    assert "driver → plug-in DTrack_drv" in result.stdout


def test_graph_json_and_mermaid(cli, setup):
    path, options = setup
    graph = json.loads(cli("config", "graph", path, "--format", "json", *options).stdout)
    kinds = {n["name"]: n["kind"] for n in graph["nodes"]}
    assert kinds["VJHead"] == "alias" and kinds["Head"] == "proxy" and kinds["Tracker"] == "device"
    assert kinds["Tracker/position_filters/Scale"] == "element"
    assert {(e["kind"], e["label"]) for e in graph["edges"]} >= {
        ("pointer", "proxy"),
        ("pointer", "device"),
        ("contains", "position_filters"),
        ("driver", "driver"),
    }
    mermaid = cli("config", "graph", path, "--format", "mermaid", *options).stdout
    assert mermaid.startswith("flowchart LR") and "-->|proxy|" in mermaid


def test_dtrack_device_is_handled_by_the_bundled_plugin(cli):
    result = cli(
        "config",
        "graph",
        CORPUS_CONFIGS / "example.dtrack.jconf",
        "--no-bundled",
        "-d",
        CORPUS_DEFINITIONS,
    )
    assert "device → dtrack 'DTrack Device'" in result.stdout
    assert "handled by → plug-in DTrack_drv" in result.stdout


@pytest.mark.parametrize(
    "name",
    ["sim.base.jconf", "example.sim.cluster.jconf", "C4.closed.jconf", "example.dtrack.jconf"],
)
def test_dot_output_is_accepted_by_graphviz(cli, name):
    require_tool("dot", "graphviz")
    result = cli("config", "graph", CORPUS_CONFIGS / name, "--format", "dot")
    assert result.exit_code == 0
    done = subprocess.run(
        ["dot", "-Tsvg"], input=result.stdout, capture_output=True, text=True, timeout=30
    )
    assert done.returncode == 0, done.stderr
    assert not done.stderr and "<svg" in done.stdout


def test_plugin_metadata_is_read_without_importing(tmp_path):
    init = write(
        tmp_path / "Fake_drv" / "__init__.py",
        'raise SystemExit("imported!")\nPLUGIN_NAME = "Fake_drv"\nELEMENT_TYPES = {"fake": ("digital",)}\n',
    )
    assert {
        t: tuple(k.value for k in kinds) for t, kinds in read_metadata(init).element_types.items()
    } == {"fake": ("digital",)}
    assert bundled_plugins(tmp_path) == {"Fake_drv": ("fake",)}
    assert plugin_for_type(tmp_path)["fake"] == "Fake_drv"
    assert plugin_for_type(drivers_dir())["dtrack"] == "DTrack_drv"
