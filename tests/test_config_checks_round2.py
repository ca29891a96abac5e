"""Configuration checks, round two (issue 17): each check with a small configuration made for
it that triggers it and one that does not."""

from __future__ import annotations

import pytest

from gadgetctl.diagnostics import Category, Severity
from gadgetctl.validate import ValidateOptions, validate_paths

from config_samples import configuration, definition, prop, version, write_definitions
from conftest import write

ALL = (Category.CONFIG, Category.XML)


@pytest.fixture
def defs(tmp_path):
    return write_definitions(tmp_path / "defs")


@pytest.fixture
def check(tmp_path, defs):
    def run(
        elements: str = "",
        *,
        files: dict[str, str] | None = None,
        together: bool = False,
        only: tuple[str, ...] | None = None,
        definitions=None,
        categories=ALL,
    ):
        files = files if files is not None else {"test.jconf": configuration(elements)}
        paths = [write(tmp_path / name, text) for name, text in files.items()]
        if only is not None:
            paths = [tmp_path / name for name in only]
        options = ValidateOptions(
            bundled=False, definition_dirs=[definitions or defs], together=together, environ={}
        )
        result = validate_paths(paths, options)
        return [d for d in result.diagnostics if d.category in categories]

    return run


def codes(found) -> list[str]:
    return [d.code for d in found]


# -- 1. stray text -------------------------------------------------------------------------


def test_stray_text_between_child_elements_is_reported_with_line_and_column(check):
    elements = (
        '      <position_proxy name="Head" version="1">\n'
        "         <device>Tracker</device>\n"
        "         8\n"
        "         <unit>0</unit>\n"
        "      </position_proxy>\n"
        '      <tracker name="Tracker" version="1"/> stray\n'
    )
    found = [d for d in check(elements) if d.code == "XML015"]
    assert [(d.line, d.column) for d in found] == [(7, 10), (10, 45)]
    assert "'8'" in found[0].message and "position_proxy" in found[0].message
    assert "'stray'" in found[1].message and "<elements>" in found[1].message
    assert all(d.severity is Severity.WARNING for d in found)


def test_text_of_a_property_and_blank_layout_are_not_stray(check):
    elements = (
        '      <position_proxy name="Head" version="1">\n'
        "         <device>Tracker</device><unit> 0 </unit>\n"
        "         <!-- a comment is not text -->\n"
        "      </position_proxy>\n"
        '      <tracker name="Tracker" version="1"/>\n'
    )
    assert check(elements) == []


def test_stray_text_in_a_definition_file(check, tmp_path):
    text = definition("widget", version(1, prop("size", "integer", defaults=("1",))))
    text = text.replace("<category>", "oops<category>")
    found = check(files={"widget.jdef": text})
    (stray,) = [d for d in found if d.code == "XML015"]
    assert stray.line == 3 and "definition_version" in stray.message
    assert text.splitlines()[2][stray.column - 1 :].startswith("oops")
    clean = definition("widget", version(1, prop("size", "integer", defaults=("1",))))
    assert [d for d in check(files={"widget.jdef": clean}) if d.code == "XML015"] == []


# -- 3. run-time version thresholds follow the definitions in use --------------------------


def test_version_threshold_is_capped_at_the_newest_version_of_the_definitions_in_use(
    check, tmp_path
):
    old_manager = (
        '      <input_manager name="IM" version="1"><driver>X_drv</driver></input_manager>\n'
    )
    # VR Juggler 3.0's definitions (input_manager up to version 2): version 1 is refused
    (refused,) = [d for d in check(old_manager) if d.code == "CFG041"]
    assert refused.severity is Severity.ERROR and "older than version 2" in refused.message
    # an older release whose input_manager definition stops at version 1 accepts it
    older = write_definitions(tmp_path / "older")
    (older / "input_manager.jdef").write_text(
        definition("input_manager", version(1, prop("driver", count=None))), encoding="utf-8"
    )
    assert check(old_manager, definitions=older) == []


# -- 4. overrides ----------------------------------------------------------------------------

TRACKER = '      <tracker name="Tracker" version="1"><port>{port}</port></tracker>\n'


def tracker(port: str = "/dev/ttyS0") -> str:
    return TRACKER.format(port=port)


def test_an_including_file_overrides_its_include(check):
    files = {
        "site.jconf": configuration(tracker("/dev/ttyUSB0"), includes=("base.jconf",)),
        "base.jconf": configuration(tracker()),
    }
    (found,) = check(files=files, only=("site.jconf",))
    assert found.code == "CFG042" and found.severity is Severity.INFO
    assert (
        "overrides" in found.message
        and "base.jconf" in found.message
        and "includes" in found.message
    )
    assert found.path.endswith("site.jconf") and found.line == 6


def test_a_later_command_line_file_overrides_an_earlier_one(check):
    files = {
        "base.jconf": configuration(tracker()),
        "local.jconf": configuration(tracker("/dev/ttyUSB0")),
    }
    (found,) = check(files=files, together=True)
    assert found.code == "CFG042" and "given after base.jconf" in found.message
    assert found.path.endswith("local.jconf")


def test_an_identical_copy_is_info_and_a_later_side_by_side_include_overrides(check):
    # two side-by-side includes: include order is load order (issue 26 item 2), so the later
    # one overrides the earlier one as a later given file would
    files = {
        "top.jconf": configuration("", includes=("a.jconf", "b.jconf")),
        "a.jconf": configuration(tracker()),
        "b.jconf": configuration(tracker("/dev/ttyUSB0")),
    }
    (found,) = check(files=files, only=("top.jconf",))
    assert (
        found.code == "CFG042"
        and found.severity is Severity.INFO
        and found.path.endswith("b.jconf")
        and "top.jconf includes b.jconf after a.jconf" in found.message
    )
    # the same, byte for byte: harmless
    files["b.jconf"] = configuration(tracker())
    (found,) = check(files=files, only=("top.jconf",))
    assert found.code == "CFG042" and "identical copy" in found.message


def test_a_duplicate_within_one_file_is_a_warning(check):
    elements = tracker() + tracker("/dev/ttyUSB0")
    (found,) = check(elements)
    assert (
        found.code == "CFG040"
        and found.severity is Severity.WARNING
        and "in this file" in found.message
    )
    assert check(tracker()) == []


# -- 2. proxies reading units beyond their device --------------------------------------------

KEYBOARD = (
    '      <keyboard_mouse_device name="Keys" version="2"/>\n'
    '      <keyboard_mouse_proxy name="Keys Proxy" version="1"><device>Keys</device></keyboard_mouse_proxy>\n'
)


def key(name: str, key_name: str) -> str:
    return (
        f'<key_pair><key_modifier_pair name="{name}" version="1"><modifier_key>ANY</modifier_key>'
        f"<key>{key_name}</key></key_modifier_pair></key_pair>"
    )


def sim_buttons(unit: int) -> str:
    return (
        KEYBOARD + '      <simulated_digital_device name="Buttons" version="2">'
        f"<keyboard_mouse_proxy>Keys Proxy</keyboard_mouse_proxy>{key('A', 'KEY_A')}{key('B', 'KEY_B')}"
        "</simulated_digital_device>\n"
        f'      <digital_proxy name="Second" version="1"><device>Buttons</device><unit>{unit}</unit></digital_proxy>\n'
    )


def bundled_check(tmp_path, text: str, name: str = "units.jconf"):
    path = write(tmp_path / name, configuration(text))
    result = validate_paths([path], ValidateOptions(environ={}))
    return [d for d in result.diagnostics if d.code == "CFG034"], path


def test_vrpn_counts_stated_by_the_configuration_bound_the_proxies(tmp_path):
    server = (
        '      <vrpn name="Server" version="3"><tracker_server>T@host</tracker_server>'
        "<button_server>B@host</button_server><analog_server>A@host</analog_server>"
        "<button_count>14</button_count></vrpn>\n"
    )
    proxies = (
        '      <digital_proxy name="Last" version="1"><device>Server</device><unit>13</unit></digital_proxy>\n'
        '      <digital_proxy name="Beyond" version="1"><device>Server</device><unit>14</unit></digital_proxy>\n'
        '      <position_proxy name="Tracker 2" version="1"><device>Server</device><unit>2</unit></position_proxy>\n'
        '      <analog_proxy name="Axis" version="1"><device>Server</device><unit>0</unit></analog_proxy>\n'
    )
    found, _ = bundled_check(tmp_path, server + proxies)
    assert [(d.line, d.severity) for d in found] == [(7, Severity.ERROR), (8, Severity.ERROR)]
    beyond, tracker = found
    assert (
        "'Beyond' reads digital unit 14" in beyond.message
        and "units 0-13 (button_count 14)" in beyond.message
    )
    assert "'Tracker 2' reads position unit 2" in tracker.message
    assert "units 0-1 (tracker_count 2 (the default))" in tracker.message
    assert "raise tracker_count" in tracker.hint


def test_fixed_counts_and_key_lists(tmp_path):
    glove = (
        '      <pinch_glove name="Pinch" version="2"><port>/dev/ttyS0</port></pinch_glove>\n'
        '      <glove_proxy name="Right" version="1"><device>Pinch</device><unit>1</unit></glove_proxy>\n'
        '      <glove_proxy name="Third" version="1"><device>Pinch</device><unit>2</unit></glove_proxy>\n'
    )
    (third,), _ = bundled_check(tmp_path, glove)
    assert "'Third' reads glove unit 2" in third.message and "units 0-1" in third.message
    (second,), _ = bundled_check(tmp_path, sim_buttons(2))
    assert "units 0-1 (2 key_pair bindings)" in second.message
    assert bundled_check(tmp_path, sim_buttons(1))[0] == []
    waves = (
        '      <waveform_device name="Wave" version="1"><analog_waveform>sine</analog_waveform></waveform_device>\n'
        '      <analog_proxy name="A1" version="1"><device>Wave</device><unit>1</unit></analog_proxy>\n'
    )
    (beyond,), _ = bundled_check(tmp_path, waves)
    assert "unit 0 (1 analog_waveform channels)" in beyond.message
    assert bundled_check(tmp_path, waves.replace("<unit>1</unit>", "<unit>0</unit>"))[0] == []


def test_counts_from_stations_scaled_counts_and_embedded_bodies(tmp_path):
    station = (
        '<stations><intersense_station name="S{0}" version="1"><digital_first>{1}</digital_first>'
        "<digital_count>{2}</digital_count></intersense_station></stations>"
    )
    text = (
        '      <intersense name="IS" version="1"><port>/dev/ttyS0</port>'
        f"{station.format(0, 0, 4)}{station.format(1, 4, 2)}</intersense>\n"
        '      <digital_proxy name="Button 6" version="1"><device>IS</device><unit>6</unit></digital_proxy>\n'
        '      <digital_proxy name="Button 5" version="1"><device>IS</device><unit>5</unit></digital_proxy>\n'
        '      <position_proxy name="Station 2" version="1"><device>IS</device><unit>2</unit></position_proxy>\n'
        '      <TUIO_drv name="T" version="1"><points>2</points></TUIO_drv>\n'
        '      <analog_proxy name="Touch 4" version="1"><device>T</device><unit>4</unit></analog_proxy>\n'
        '      <analog_proxy name="Touch 3" version="1"><device>T</device><unit>3</unit></analog_proxy>\n'
        '      <optitrack name="O" version="2"><rigid_body><optitrack_rigid_body name="B" version="1">'
        "<body_index>1</body_index></optitrack_rigid_body></rigid_body></optitrack>\n"
        '      <position_proxy name="Body 1" version="1"><device>O</device><unit>1</unit></position_proxy>\n'
    )
    found, _ = bundled_check(tmp_path, text)
    assert [(d.message.split("'")[1], d.message.split(" has ")[1], d.hint) for d in found] == [
        (
            "Button 6",
            "units 0-5 (stations' digital_first + digital_count); the proxy only ever reads default data",
            "Raise a station's digital_count to cover the unit.",
        ),
        (
            "Station 2",
            "units 0-1 (2 stations); the proxy only ever reads default data",
            "Add an intersense_station for each position unit the proxies read.",
        ),
        (
            "Touch 4",
            "units 0-3 (2 per points (2)); the proxy only ever reads default data",
            "Units 2i and 2i+1 are the x and y of touch slot i.",
        ),
        (
            "Body 1",
            "unit 0 (1 embedded bodies and markers); the proxy only ever reads default data",
            "Add a rigid_body or marker for each unit.",
        ),
    ]


def test_config_pending_applies_the_same_rule(tmp_path, cli):
    _, path = bundled_check(tmp_path, sim_buttons(2))
    result = cli("config", "pending", path, "--format", "json")
    import json

    report = json.loads(result.stdout)
    (problem,) = [d for d in report["diagnostics"] if d["code"] == "CFG034"]
    (validated,), _ = bundled_check(tmp_path, sim_buttons(2))
    assert problem["message"] == validated.message and problem["line"] == validated.line
    assert result.exit_code == 1
    _, path = bundled_check(tmp_path, sim_buttons(1), "fine.jconf")
    assert cli("config", "pending", path).exit_code == 0


# -- 5. reporting once, one rule for malformed includes, search path, unknown types ---------

BROKEN = '<?xml version="1.0"?>\n<configuration><elements><alias name="A" version="1"></elements></configuration>\n'
KEYS_ONLY = '      <keyboard_mouse_device name="Keys" version="2"/>\n'


def test_a_malformed_file_given_and_included_is_reported_once(check, tmp_path):
    files = {
        "main.jconf": configuration(tracker(), includes=("broken.jconf",)),
        "broken.jconf": BROKEN,
    }
    found = check(files=files)
    assert codes(found) == ["XML001"] and found[0].path.endswith("broken.jconf")
    # included only: still reported, once
    assert codes(check(files=files, only=("main.jconf",))) == ["XML001"]


@pytest.mark.parametrize(
    "command", [("config", "show"), ("config", "graph"), ("config", "pending"), ("monitor",)]
)
def test_every_command_refuses_a_malformed_include_the_same_way(tmp_path, cli, command):
    main = write(tmp_path / "main.jconf", configuration(KEYS_ONLY, includes=("broken.jconf",)))
    write(tmp_path / "broken.jconf", BROKEN)
    extra = ("--duration", "0.1", "--format", "table") if command == ("monitor",) else ()
    result = cli(*command, main, *extra)
    assert result.exit_code == 2
    assert "broken.jconf:2:" in result.stderr and "cannot load the configuration" in result.stderr
    write(tmp_path / "broken.jconf", configuration(""))
    assert cli(*command, main, *extra).exit_code == 0


def test_a_repeated_search_path_entry_is_ignored(tmp_path, cli, defs):
    path = write(tmp_path / "t.jconf", configuration(tracker()))
    result = cli("validate", "--no-bundled", "-d", defs, "-d", defs, "--format", "json", path)
    assert result.exit_code == 0 and "DEF021" not in result.stdout
    # two different directories defining the same type still shadow
    other = write_definitions(tmp_path / "other")
    result = cli("validate", "--no-bundled", "-d", defs, "-d", other, "--format", "json", path)
    assert "DEF021" in result.stdout


def test_elements_of_unknown_type_are_shown_as_such_and_do_not_fail(tmp_path, cli):
    path = write(
        tmp_path / "unknown.jconf",
        configuration(KEYS_ONLY + '      <mystery_box name="Box" version="1"/>\n'),
    )
    result = cli("config", "pending", path)
    assert result.exit_code == 0, result.stdout
    assert (
        "info DRV040 Box is of type mystery_box" in result.stdout
        and "1 of unknown type" in result.stdout
    )
    result = cli("monitor", path, "--duration", "0.2", "--format", "table")
    assert result.exit_code == 0, result.stdout
    (row,) = [line for line in result.stdout.splitlines() if line.startswith("Box ")]
    assert "unknown type" in row and "pending" not in row
    # a real pending element still fails both
    stuck = (
        KEYS_ONLY
        + '      <keyboard_mouse_proxy name="KP" version="1"><device>Nowhere</device></keyboard_mouse_proxy>\n'
    )
    path = write(tmp_path / "stuck.jconf", configuration(stuck))
    assert cli("config", "pending", path).exit_code == 1


# -- 6. upgrade: dropped properties, agreement with validate, the file's own spelling ---------


def upgrade(cli, defs, *args):
    return cli("upgrade", "--no-bundled", "-d", defs, *args)


def diff_lines(text: str) -> list[str]:
    return [
        line for line in text.splitlines() if line[:1] in "+-" and line[:3] not in ("+++", "---")
    ]


def test_drop_removed_takes_out_properties_the_newest_definition_no_longer_has(
    tmp_path, cli, defs, check
):
    elements = (
        '      <tracker name="Tracker" version="1">\n'
        "         <port>/dev/ttyS1</port>\n"
        "         <device_host />\n"
        "      </tracker>\n"
    )
    path = write(tmp_path / "old.jconf", configuration(elements))
    assert "CFG021" in codes(check(only=("old.jconf",)))
    # without the option nothing changes: the element is at its newest version
    assert upgrade(cli, defs, "--check", path).exit_code == 0
    listing = upgrade(cli, defs, "--check", "--drop-removed", path)
    assert listing.exit_code == 1 and "tracker 'Tracker': removed device_host" in listing.stdout
    result = upgrade(cli, defs, "--diff", "--drop-removed", path)
    assert diff_lines(result.stdout) == ["-         <device_host />"]
    assert upgrade(cli, defs, "--in-place", "--no-backup", "--drop-removed", path).exit_code == 0
    assert check(only=("old.jconf",)) == []


def test_upgrade_leaves_alone_what_validate_does_not_report_as_outdated(tmp_path, cli, defs, check):
    # an outdated gizmo embedded in an element of unknown type: validate says only CFG010
    elements = (
        '      <mystery name="M" version="1">\n'
        '         <parts><gizmo name="G" version="1"><size>2</size></gizmo></parts>\n'
        "      </mystery>\n"
    )
    path = write(tmp_path / "unknown.jconf", configuration(elements))
    assert codes(check(only=("unknown.jconf",))) == ["CFG010"]
    # upgrade --check cannot vouch for a file it cannot check (issue 25 item 3): it fails with
    # the CFG010 validate gives, and claims nothing about the gizmo validate does not report
    unknown = upgrade(cli, defs, "--check", path)
    assert unknown.exit_code == 1 and "CFG010" in unknown.stderr
    assert "gizmo" not in unknown.stdout + unknown.stderr
    # the same gizmo embedded where the definition allows it is outdated for both
    known = write(tmp_path / "known.jconf", configuration(elements.replace("mystery", "holder")))
    assert "CFG012" in codes(check(only=("known.jconf",)))
    listing = upgrade(cli, defs, "--check", known)
    assert listing.exit_code == 1 and "gizmo 'G': version 1 -> 3" in listing.stdout


def test_upgrade_diff_changes_only_the_outdated_elements_lines_in_the_files_spelling(
    tmp_path, cli, defs
):
    elements = (
        "      <tracker version='1' name='Before'>\n"
        "         <port />\n"
        "      </tracker>\n"
        "      <input_manager version='1' name='IM'>\n"
        "\t\t<driver>X_drv</driver>\n"
        "\t\t<driver />\n"
        "      </input_manager>\n"
        '      <tracker name="After"   version="1"><port/></tracker>\n'
    )
    path = write(tmp_path / "one.jconf", configuration(elements))
    result = upgrade(cli, defs, "--diff", path)
    assert result.exit_code == 0
    # only the version attribute changes, in its own quotes and place; the self-closing
    # <driver /> and the tab indentation stay as they are
    assert diff_lines(result.stdout) == [
        "-      <input_manager version='1' name='IM'>",
        "+      <input_manager version='2' name='IM'>",
    ]


def test_a_broken_definition_given_and_on_the_search_path_is_reported_once(tmp_path, cli):
    folder = write(
        tmp_path / "defs" / "bad.jdef",
        '<?xml version="1.0"?>\n<definition name="x"><oops></definition>\n',
    ).parent
    result = cli("validate", folder, "-d", folder, "--format", "json")
    import json

    found = [d["code"] for d in json.loads(result.stdout)]
    assert found == ["XML001"]
    # on the search path only, it is still reported
    other = write(tmp_path / "t.jconf", configuration(""))
    result = cli("validate", other, "-d", folder, "--format", "json")
    assert [d["code"] for d in json.loads(result.stdout)] == ["DEF020"]


def test_a_renamed_property_is_rewritten_in_its_place_and_comments_stay(tmp_path, cli, defs):
    elements = (
        '      <gizmo name="G" version="2">\r\n'
        "         <!-- the size in centimetres -->\r\n"
        "         <size>4</size>\r\n"
        "         <color>blue</color>\r\n"
        "      </gizmo>\r\n"
    )
    path = tmp_path / "crlf.jconf"
    path.write_bytes(configuration(elements).replace("\n", "\r\n").replace("\r\r", "\r").encode())
    result = upgrade(cli, defs, "--diff", path)
    assert diff_lines(result.stdout.replace("\r", "")) == [
        '-      <gizmo name="G" version="2">',
        '+      <gizmo name="G" version="3">',
        "-         <size>4</size>",
        "+         <extent>4</extent>",
        '+      <gizmo_label name="G label" version="1"/>',
    ]
    upgraded = upgrade(cli, defs, path).stdout
    assert "<!-- the size in centimetres -->\r\n         <extent>4</extent>\r\n" in upgraded
