"""Configuration checks, round three (issue 26): each item reproduced by a small file made
for it."""

from __future__ import annotations

from pathlib import Path

from gadgetctl.diagnostics import Category, Severity
from gadgetctl.validate import ValidateOptions, validate_paths

from jccl_samples import CONFIG_NS

ALL = (Category.CONFIG, Category.XML, Category.SCHEMA)


def jconf(body: str, includes: tuple[str, ...] = ()) -> str:
    lines = "".join(f"   <include>{name}</include>\n" for name in includes)
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
        f'<configuration xmlns="{CONFIG_NS}" name="t">\n{lines}'
        f"   <elements>\n{body}   </elements>\n</configuration>\n"
    )


def findings(*paths: Path, together: bool = False, environ=None):
    options = ValidateOptions(together=together, environ=environ or {})
    result = validate_paths(list(paths), options)
    return [d for d in result.diagnostics if d.category in ALL]


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


# -- 1. editable enumerations take any text ---------------------------------------------------


def manager(driver: str) -> str:
    return (
        '      <input_manager name="Input" version="2">\n'
        f"         <driver>{driver}</driver>\n"
        "      </input_manager>\n"
    )


def test_a_plugin_spelled_differently_from_the_enumeration_label_is_no_finding(tmp_path):
    # 'Optitrack_drv' is the label; the plug-in (ours and VR Juggler's Unix one) is OptiTrack_drv.
    assert findings(write(tmp_path / "a.jconf", jconf(manager("OptiTrack_drv")))) == []


def test_a_case_variant_of_a_label_without_such_a_plugin_is_only_a_suggestion(tmp_path):
    (found,) = findings(write(tmp_path / "a.jconf", jconf(manager("dtrack_drv"))))
    assert found.code == "CFG027" and found.severity is Severity.INFO
    assert "'DTrack_drv'" in found.hint and "as written" in found.message
    assert findings(write(tmp_path / "b.jconf", jconf(manager("MyOwnTracker_drv")))) == []


def test_a_case_variant_naming_an_element_of_that_exact_name_is_no_suggestion(tmp_path):
    # (an editable enumeration's text may name anything; an element of that name is meant)
    named = manager("dtrack_drv") + alias("dtrack_drv", "Head")
    found = findings(write(tmp_path / "a.jconf", jconf(named)))
    assert "CFG027" not in [d.code for d in found]


# -- 2. a later sibling include overrides an earlier one ----------------------------------------


def alias(name: str, proxy: str) -> str:
    return f'      <alias name="{name}" version="1"><proxy>{proxy}</proxy></alias>\n'


def sim_head(name: str) -> str:
    return (
        f'      <position_proxy name="{name}" version="1">\n'
        "         <device>Sim</device><unit>0</unit>\n"
        "      </position_proxy>\n"
    )


def test_a_later_include_overriding_an_earlier_sibling_include_is_an_override(tmp_path):
    write(tmp_path / "base.jconf", jconf(alias("VJHead", "Head A") + sim_head("Head A")))
    write(tmp_path / "role.jconf", jconf(alias("VJHead", "Head B") + sim_head("Head B")))
    system = write(tmp_path / "system.jconf", jconf("", includes=("base.jconf", "role.jconf")))
    dupes = [d for d in findings(system) if d.code in ("CFG040", "CFG042")]
    assert [(d.code, d.severity) for d in dupes] == [("CFG042", Severity.INFO)]
    assert "system.jconf includes role.jconf after base.jconf" in dupes[0].message
    # the same pair given in that order is the same finding
    together = findings(tmp_path / "base.jconf", tmp_path / "role.jconf", together=True)
    assert [d.code for d in together if d.code in ("CFG040", "CFG042")] == ["CFG042"]


# -- 4. one fact, one finding ---------------------------------------------------------------


def test_an_identical_copy_is_worded_the_same_in_both_modes(tmp_path):
    write(tmp_path / "a.jconf", jconf(alias("VJHead", "Head A") + sim_head("Head A")))
    write(tmp_path / "b.jconf", jconf(alias("VJHead", "Head A")))
    main = write(tmp_path / "main.jconf", jconf("", includes=("a.jconf", "b.jconf")))
    alone = [d for d in findings(main) if d.code == "CFG042"]
    together = [
        d
        for d in findings(tmp_path / "a.jconf", tmp_path / "b.jconf", together=True)
        if d.code == "CFG042"
    ]
    assert len(alone) == len(together) == 1
    assert " repeats " in alone[0].message and " repeats " in together[0].message
    assert "(an identical copy" in alone[0].message and "(an identical copy" in together[0].message


def test_text_directly_inside_elements_or_configuration_is_one_finding(tmp_path):
    text = jconf("      stray\n" + alias("VJHead", "Head A") + sim_head("Head A")).replace(
        "   <elements>", "   oops\n   <elements>"
    )
    found = findings(write(tmp_path / "a.jconf", text))
    assert sorted(d.code for d in found if d.code[:3] in ("XML", "SCH")) == ["XML015", "XML015"]
    # text in an element without child elements is still a schema error
    bare = jconf("").replace("   <elements>\n   </elements>", "   <elements>oops</elements>")
    assert [d.code for d in findings(write(tmp_path / "b.jconf", bare))] == ["SCH001"]


# -- 3. checks that hold in every version run before upgrade too -------------------------------


def test_an_old_simulated_device_without_a_keyboard_proxy_is_reported_before_upgrade(tmp_path):
    old = (
        '      <simulated_analog_device name="Sim" version="1">\n'
        "         <event_window_proxy></event_window_proxy>\n"
        "      </simulated_analog_device>\n"
    )
    found = findings(write(tmp_path / "a.jconf", jconf(old)))
    assert {"CFG012", "CFG033"} <= {d.code for d in found}
    (required,) = [d for d in found if d.code == "CFG033"]
    assert "event_window_proxy is empty" in required.message and required.line == 6
    assert "never sees a key" in required.message


# -- 5. upgrade output follows the file ----------------------------------------------------------


def upgraded(tmp_path: Path, body: str, *, drop_removed: bool = False) -> str:
    from gadgetctl.jccl.repository import default_repository
    from gadgetctl.jccl.upgrade import upgrade_bytes

    data = jconf(body).encode()
    result = upgrade_bytes(
        tmp_path / "a.jconf", data, default_repository([]), drop_removed=drop_removed
    )
    assert not result.problems, result.problems
    assert result.upgraded is not None
    return result.upgraded.decode()


def test_new_properties_of_a_one_line_element_stay_on_its_line(tmp_path):
    body = (
        '      <display_window name="W" version="5"><size>640</size><size>480</size>'
        "<pipe>0</pipe></display_window>\n"
    )
    text = upgraded(tmp_path, body)
    (line,) = [line for line in text.splitlines() if "display_window" in line]
    assert line.startswith('      <display_window name="W" version="6"><size>640</size>')
    assert "<allow_mouse_locking>true</allow_mouse_locking></display_window>" in line


def test_new_empty_elements_are_written_as_the_file_writes_them(tmp_path):
    body = (
        '      <display_window name="W" version="3">\n'
        "         <size>640</size>\n"
        "         <pipe>0</pipe>\n"
        "         <act_as_event_source />\n"
        "      </display_window>\n"
    )
    text = upgraded(tmp_path, body)
    assert "<keyboard_mouse_device_name />" in text and "<keyboard_mouse_device_name/>" not in text


def test_a_renamed_property_left_in_a_newer_element_is_carried_not_dropped(tmp_path):
    body = (
        '      <display_system name="Pipes" version="3">\n'
        "         <number_of_pipes>1</number_of_pipes>\n"
        "         <x11_pipes>:0.0</x11_pipes>\n"
        "         <use_swap_group>false</use_swap_group>\n"
        "      </display_system>\n"
    )
    (found,) = findings(write(tmp_path / "a.jconf", jconf(body)))
    assert found.code == "CFG021" and "pipes" in found.hint and "--drop-removed" not in found.hint
    for drop in (False, True):
        text = upgraded(tmp_path, body, drop_removed=drop)
        assert "<pipes>:0.0</pipes>" in text and "x11_pipes" not in text


# -- 6. config show gives values as VR Juggler reads them ----------------------------------------


def test_config_show_gives_a_number_that_does_not_parse_as_it_is_read(tmp_path, cli):
    import json

    body = (
        '      <dtrack name="Input" version="1">\n'
        "         <command_port>abc</command_port>\n"
        "      </dtrack>\n"
    )
    path = write(tmp_path / "a.jconf", jconf(body))
    shown = cli("config", "show", path, "--element", "Input")
    (line,) = [line for line in shown.stdout.splitlines() if "command_port" in line]
    assert line.split()[1] == "0" and "'abc' does not parse as an integer" in line
    data = json.loads(cli("config", "show", path, "--element", "Input", "--format", "json").stdout)
    (prop,) = [p for p in data[0]["properties"] if p["name"] == "command_port"]
    assert prop["values"][0]["value"] == "0" and prop["values"][0]["written"] == "abc"


# -- 7. defs sees the definitions of installed plug-ins ------------------------------------------


def test_defs_list_and_show_see_a_plugin_installed_through_its_entry_point(
    tmp_path, monkeypatch, cli
):
    import sys

    site = tmp_path / "site"
    plugin = site / "gadget_defs_extra" / "plug"
    plugin.mkdir(parents=True)
    (site / "gadget_defs_extra" / "__init__.py").write_text("")
    (plugin / "__init__.py").write_text(
        'GADGETCTL_API_VERSION = 1\nPLUGIN_NAME = "Extra_drv"\n'
        'ELEMENT_TYPES = {"extra_knob": ("analog",)}\n'
    )
    (plugin / "extra_knob.jdef").write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<?org-vrjuggler-jccl-settings definition.version="3.1"?>\n'
        '<definition xmlns="http://www.vrjuggler.org/jccl/xsd/3.1/definition" name="extra_knob">\n'
        '  <definition_version version="1" label="Extra knob">\n'
        "    <abstract>false</abstract><help>A knob.</help><parent>analog_device</parent>\n"
        "    <category>/Devices/Analog</category>\n"
        '    <property valuetype="integer" variable="false" name="knob_count">\n'
        '      <help>Knobs.</help><value label="Knobs" defaultvalue="1"/>\n'
        "    </property>\n"
        "    <upgrade_transform/>\n"
        "  </definition_version>\n"
        "</definition>\n"
    )
    dist = site / "gadget_defs_extra-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: gadget-defs-extra\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text(
        "[gadgetctl.drivers]\nExtra_drv = gadget_defs_extra.plug\n"
    )
    monkeypatch.syspath_prepend(str(site))
    listed = cli("defs", "list", "--format", "json")
    assert listed.exit_code == 0 and "extra_knob" in listed.stdout
    shown = cli("defs", "show", "extra_knob")
    assert shown.exit_code == 0 and "knob_count" in shown.stdout
    assert not any(m.startswith("gadget_defs_extra") for m in sys.modules)  # read, not imported


# -- 8. a search-path entry naming an unset variable -------------------------------------------


def test_a_definition_path_entry_with_an_unset_variable_is_named_and_skipped(tmp_path, monkeypatch):
    defs = tmp_path / "defs"
    defs.mkdir()
    (defs / "extra_knob.jdef").write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<?org-vrjuggler-jccl-settings definition.version="3.1"?>\n'
        '<definition xmlns="http://www.vrjuggler.org/jccl/xsd/3.1/definition" name="extra_knob">\n'
        '  <definition_version version="1" label="Extra knob">\n'
        "    <abstract>false</abstract><help>A knob.</help><parent/>\n"
        "    <category>/Devices</category><upgrade_transform/>\n"
        "  </definition_version>\n"
        "</definition>\n"
    )
    # with ${NOPE} read as empty the entry would be exactly the directory above
    monkeypatch.setenv("JCCL_DEFINITION_PATH", "${NOPE}" + str(defs))
    monkeypatch.delenv("NOPE", raising=False)
    config = write(tmp_path / "a.jconf", jconf('      <extra_knob name="K" version="1"/>\n'))
    result = validate_paths([config], ValidateOptions(environ={}))
    by_code = {d.code: d for d in result.diagnostics}
    assert by_code["DEF022"].path == "$JCCL_DEFINITION_PATH"
    assert "skipped" in by_code["DEF022"].message
    assert "DEF023" not in by_code
    assert "CFG010" in by_code  # the directory was not searched
