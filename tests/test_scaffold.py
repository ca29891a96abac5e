"""`gadgetctl scaffold driver`: names, refusals, the template language and the command line.

The generated drivers themselves are run in test_scaffold_drivers.py.
"""

from __future__ import annotations

import json

import pytest

from gadgetctl.scaffold import DriverNames, DriverSpec, ScaffoldError, generate, scaffold
from gadgetctl.scaffold.generate import py_import, py_literal
from gadgetctl.scaffold.render import TemplateError, evaluate, render, select_lines, template_text

# -- names ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "camel", "plugin", "element_type"),
    [
        ("AcmeWand", "AcmeWand", "AcmeWand_drv", "acme_wand"),
        ("acme_wand", "AcmeWand", "AcmeWand_drv", "acme_wand"),
        ("AcmeWand_drv", "AcmeWand", "AcmeWand_drv", "acme_wand"),
        ("MyHTTPGlove", "MyHTTPGlove", "MyHTTPGlove_drv", "my_http_glove"),
        ("wand2_x", "Wand2X", "Wand2X_drv", "wand2_x"),
        ("Wand", "Wand", "Wand_drv", "wand"),
        ("  spaced  ", "Spaced", "Spaced_drv", "spaced"),
    ],
)
def test_names_are_derived_from_camel_or_snake_case(name, camel, plugin, element_type):
    names = DriverNames.parse(name)
    assert (names.camel, names.plugin, names.element_type) == (camel, plugin, element_type)


@pytest.mark.parametrize(
    ("name", "reason"),
    [
        ("", "empty"),
        ("_drv", "empty"),
        ("3dMouse", "not a valid name"),
        ("acme-wand", "not a valid name"),
        ("Acme Wand", "not a valid name"),
        ("Akmé", "not a valid name"),
        ("_acme", "may not start or end"),
        ("acme__wand", "may not start or end"),
        ("acme_Wand", "mixes cases"),
        ("acmeWand", "starts with a capital letter"),
        ("XmlReader", "XML reserves"),
        ("match", "Python keyword"),
        ("Analog", "already uses"),
        ("A" + "b" * 32, "too long"),
    ],
)
def test_invalid_names_are_refused_with_the_reason(name, reason):
    with pytest.raises(ScaffoldError, match=reason):
        DriverNames.parse(name)


@pytest.mark.parametrize(
    ("name", "clash"),
    [
        ("PinchGlove", "standard definition pinch_glove"),
        ("pinch_glove", "standard definition pinch_glove"),
        ("DTrack", "bundled driver plug-in DTrack_drv"),
        ("Dtrack", "standard definition dtrack"),
        ("LinuxJoydev", "standard definition linux_joydev"),
        ("WaveformDevice", "standard definition waveform_device"),
        ("SimulatedAnalogDevice", "standard definition simulated_analog_device"),
        ("digital_proxy", "standard definition digital_proxy"),
        ("InputManager", "standard definition input_manager"),
        ("IS900", "bundled driver plug-in IS900_drv"),
        (
            "DirectXJoystick",
            "upstream Gadgeteer driver plug-in DirectXJoystick_drv",
        ),  # Windows only
    ],
)
def test_names_of_standard_definitions_and_plugins_are_refused(name, clash):
    with pytest.raises(ScaffoldError, match=f"clashes with the {clash}"):
        DriverNames.parse(name)


def test_unknown_types_transports_and_odd_vendors_are_refused():
    with pytest.raises(ScaffoldError, match="unknown device type 'keyboard'"):
        DriverSpec.create("Wand", ["keyboard"])
    with pytest.raises(ScaffoldError, match="unknown transport 'usb'"):
        DriverSpec.create("Wand", [], "usb")
    for vendor in ("<Acme>", "Acme -- Corp", "x" * 41):
        with pytest.raises(ScaffoldError, match="--vendor"):
            DriverSpec.create("Wand", vendor=vendor)


def test_types_keep_their_order_without_repeats_and_default_to_digital():
    assert DriverSpec.create("Wand").types == ("digital",)
    spec = DriverSpec.create("Wand", ["Glove", "digital", "glove"], "UDP")
    assert spec.types == ("glove", "digital")
    assert spec.transport == "udp"


# -- the template language -------------------------------------------------------------------


def test_conditions_combine_flags():
    flags = {"a": True, "b": False, "c": True}
    assert evaluate("a and not b", flags)
    assert evaluate("b or (a and c)", flags)
    assert not evaluate("not (a or b)", flags)
    with pytest.raises(TemplateError, match="unknown flag 'd'"):
        evaluate("a or d", flags)
    with pytest.raises(TemplateError, match="ends too early"):
        evaluate("(a or b", flags)
    with pytest.raises(TemplateError, match="unbalanced"):
        evaluate("(a or b c", flags)


def test_directives_choose_lines(monkeypatch):
    texts = {
        "main": "start\n%if a\n  A\n%elif b\n  B\n%else\n  neither\n%end\n%# dropped\n%include part\n$value\n",
        "part": "%if not a\npart for not a\n%end\n",
        "broken": "%if a\nno end\n",
    }
    monkeypatch.setattr("gadgetctl.scaffold.render.template_text", texts.__getitem__)
    assert render("main", {"a": True, "b": True}, {"value": 1}) == "start\n  A\n1\n"
    assert (
        render("main", {"a": False, "b": True}, {"value": 2}) == "start\n  B\npart for not a\n2\n"
    )
    assert (
        render("main", {"a": False, "b": False}, {"value": 3})
        == "start\n  neither\npart for not a\n3\n"
    )
    with pytest.raises(TemplateError, match="without %end"):
        select_lines("broken", {"a": True})
    with pytest.raises(TemplateError, match="KeyError"):
        render("main", {"a": True, "b": True}, {})


def test_every_template_renders_for_every_transport():
    for transport in ("serial", "udp", "tcp", "file", "none"):
        for package in (False, True):
            spec = DriverSpec.create("Wand", ["analog", "string"], transport, package=package)
            files = {f.path.name: f.text for f in generate(spec)}
            assert not [name for name, text in files.items() if "${" in text or "\n%" in text]
            assert ("emulator.py" in files) is (transport != "none")
            assert ("pyproject.toml" in files) is package
    assert template_text("standalone.py.tmpl").count("PROTOCOL") >= 2


def test_python_layout_follows_ruff():
    assert py_literal("X = ", {"a": ("b",)}) == ['X = {"a": ("b",)}']
    long = py_literal("ELEMENT_TYPES = ", {"x" * 30: ("digital", "analog", "position", "glove")})
    assert long == [
        "ELEMENT_TYPES = {",
        '    "' + "x" * 30 + '": ("digital", "analog", "position", "glove"),',
        "}",
    ]
    longer = py_literal("ELEMENT_TYPES = ", {"x" * 40: ("digital", "analog", "position", "glove")})
    assert longer[1:3] == ['    "' + "x" * 40 + '": (', '        "digital",']
    assert py_import("m", ["decode", "KINDS", "Wand"]) == "from m import KINDS, Wand, decode"
    assert py_import("m", ["n" * 30, "o" * 30, "p" * 30]).splitlines()[1:] == [
        "    " + "n" * 30 + ",",
        "    " + "o" * 30 + ",",
        "    " + "p" * 30 + ",",
        ")",
    ]


# -- what is generated ---------------------------------------------------------------------------


def test_a_folder_plugin_has_the_layout_of_the_bundled_drivers(tmp_path):
    spec = DriverSpec.create(
        "AcmeWand", ["digital", "analog"], "serial", vendor="Acme", directory=tmp_path
    )
    result = scaffold(spec)
    folder = tmp_path / "AcmeWand_drv"
    assert sorted(str(p.relative_to(folder)) for p in result.paths) == [
        "README.md",
        "__init__.py",
        "acme_wand.jdef",
        "emulator.py",
        "example.jconf",
        "standalone.py",
        "tests/conftest.py",
        "tests/test_acme_wand.py",
        "wrapper.py",
    ]
    init = (folder / "__init__.py").read_text()
    assert 'PLUGIN_NAME = "AcmeWand_drv"' in init
    assert 'ELEMENT_TYPES = {"acme_wand": ("digital", "analog")}' in init
    assert 'TRANSPORTS = {"acme_wand": {"kind": "serial", "port": "port", "baud": "baud"}}' in init
    wrapper = (folder / "wrapper.py").read_text()
    assert "class AcmeWandDevice(Digital, Analog):" in wrapper
    assert "        super().config(access)\n" in wrapper
    jdef = (folder / "acme_wand.jdef").read_text()
    assert "<parent>digital_device</parent>\n    <parent>analog_device</parent>" in jdef
    assert 'label="Acme AcmeWand"' in jdef
    from gadgetctl.input.plugins.metadata import read_metadata

    meta = read_metadata(folder / "__init__.py")
    assert meta.problems == []
    assert meta.transports == {"acme_wand": [{"kind": "serial", "port": "port", "baud": "baud"}]}


def test_a_package_has_an_entry_point_and_a_src_layout(tmp_path):
    spec = DriverSpec.create("AcmeWand", ["position"], "tcp", package=True, directory=tmp_path)
    scaffold(spec)
    project = tmp_path / "gadgetctl-acme-wand"
    pyproject = (project / "pyproject.toml").read_text()
    assert '[project.entry-points."gadgetctl.drivers"]\nAcmeWand_drv = "AcmeWand_drv"' in pyproject
    assert 'packages = ["src/AcmeWand_drv"]' in pyproject
    assert (project / "src" / "AcmeWand_drv" / "acme_wand.jdef").is_file()
    assert (project / "README.md").is_file()
    assert not (project / "src" / "AcmeWand_drv" / "README.md").exists()


def test_gesture_devices_get_no_gesture_proxy_and_say_why(tmp_path):
    scaffold(DriverSpec.create("Gestures", ["gesture"], "none", directory=tmp_path))
    jconf = (tmp_path / "Gestures_drv" / "example.jconf").read_text()
    assert "gesture_proxy" in jconf and "<gesture_proxy " not in jconf
    assert (
        "<parent>input_device</parent>" in (tmp_path / "Gestures_drv" / "gestures.jdef").read_text()
    )


# -- the command line ------------------------------------------------------------------------------


def test_scaffold_driver_writes_and_shows_the_next_steps(cli, tmp_path):
    result = cli(
        "scaffold",
        "driver",
        "AcmeWand",
        "--type",
        "digital",
        "-t",
        "analog",
        "--transport",
        "udp",
        "--dir",
        tmp_path,
    )
    assert result.exit_code == 0, result.stderr
    assert result.stdout.startswith(
        "AcmeWand: plug-in AcmeWand_drv, element type acme_wand, digital and analog"
    )
    assert "created" in result.stdout and "gadgetctl monitor" in result.stdout
    assert (tmp_path / "AcmeWand_drv" / "emulator.py").is_file()


def test_dry_run_writes_nothing(cli, tmp_path):
    result = cli(
        "scaffold", "driver", "AcmeWand", "--dir", tmp_path / "new", "--dry-run", "--package"
    )
    assert result.exit_code == 0, result.stderr
    assert "would create" in result.stdout and "pyproject.toml" in result.stdout
    assert not (tmp_path / "new").exists()
    data = json.loads(
        cli("scaffold", "driver", "AcmeWand", "--dir", tmp_path, "--dry-run", "-f", "json").stdout
    )
    assert data["written"] is False and data["plugin"] == "AcmeWand_drv"
    assert data["files"][0] == str(tmp_path / "AcmeWand_drv" / "__init__.py")
    assert not list(tmp_path.iterdir())


def test_an_existing_directory_needs_force(cli, tmp_path):
    assert cli("scaffold", "driver", "AcmeWand", "--dir", tmp_path).exit_code == 0
    folder = tmp_path / "AcmeWand_drv"
    (folder / "standalone.py").write_text("# my protocol\n")
    (folder / "notes.txt").write_text("mine\n")
    again = cli("scaffold", "driver", "AcmeWand", "--dir", tmp_path)
    assert again.exit_code == 2
    assert "already exists" in again.stderr and "--force" in again.stderr
    assert (folder / "standalone.py").read_text() == "# my protocol\n"
    forced = cli("scaffold", "driver", "AcmeWand", "--dir", tmp_path, "--force")
    assert forced.exit_code == 0, forced.stderr
    assert "PROTOCOL" in (folder / "standalone.py").read_text()
    assert (folder / "notes.txt").read_text() == "mine\n"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["3dMouse"], "is not a valid name"),
        (["PinchGlove"], "clashes with the standard definition pinch_glove"),
        (["DTrack"], "clashes with the bundled driver plug-in DTrack_drv"),
        (["Wand", "--type", "keyboard"], "invalid value for '--type'"),
        (["Wand", "--transport", "usb"], "invalid value for '--transport'"),
        (["Wand", "--vendor", "<b>"], "--vendor"),
    ],
)
def test_refusals_exit_2_with_a_clear_message(cli, tmp_path, args, message):
    result = cli("scaffold", "driver", *args, "--dir", tmp_path)
    assert result.exit_code == 2
    assert message in result.stderr
    assert not list(tmp_path.iterdir())


def test_dir_must_be_a_directory(cli, tmp_path):
    (tmp_path / "file").write_text("")
    result = cli("scaffold", "driver", "Wand", "--dir", tmp_path / "file")
    assert result.exit_code == 2 and "not a directory" in result.stderr
