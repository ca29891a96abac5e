"""Configuration checks: each check with a small configuration that triggers it and one that
does not (issue 4, item 2)."""

from __future__ import annotations

import pytest

from gadgetctl.diagnostics import Category, Severity
from gadgetctl.validate import ValidateOptions, validate_paths

from config_samples import configuration, write_definitions
from conftest import write

TRACKER = """      <tracker name="Tracker" version="1">
{body}      </tracker>
"""


@pytest.fixture
def check(tmp_path):
    definitions = write_definitions(tmp_path / "defs")

    def run(
        elements: str = "",
        *,
        files: dict[str, str] | None = None,
        together: bool = False,
        environ: dict[str, str] | None = None,
        only: tuple[str, ...] | None = None,
        categories: tuple[Category, ...] = (Category.CONFIG,),
    ):
        files = files if files is not None else {"test.jconf": configuration(elements)}
        paths = [write(tmp_path / name, text) for name, text in files.items()]
        if only is not None:
            paths = [tmp_path / name for name in only]
        options = ValidateOptions(
            bundled=False,
            definition_dirs=[definitions],
            together=together,
            environ=environ if environ is not None else {},
        )
        result = validate_paths(paths, options)
        return [d for d in result.diagnostics if d.category in categories]

    return run


def codes(found) -> list[str]:
    return [d.code for d in found]


def tracker(body: str) -> str:
    return TRACKER.format(body=body)


# -- element types, versions, names ------------------------------------------------------


def test_unknown_type_is_reported_with_close_names_and_the_search_path(check):
    (found,) = check('      <trackr name="T" version="1"/>\n')
    assert found.code == "CFG010" and found.severity is Severity.ERROR
    assert "trackr" in found.message and found.line == 5
    assert "Did you mean tracker" in found.hint and "defs" in found.hint
    assert check('      <tracker name="T" version="1"/>\n') == []


def test_abstract_type_cannot_be_instantiated(check):
    assert codes(check('      <positional_device name="P" version="1"/>\n')) == ["CFG011"]
    assert check('      <tracker name="P" version="1"/>\n') == []


def test_older_element_is_flagged_and_judged_by_its_own_version(check):
    found = check(
        '      <input_manager name="IM" version="1"><driver>X_drv</driver></input_manager>\n'
    )
    assert "CFG012" in codes(found)
    older = next(d for d in found if d.code == "CFG012")
    assert "version 1" in older.message and "version 2" in older.message and "upgrade" in older.hint
    # driver is a property of version 1: no unknown-property finding
    assert "CFG020" not in codes(found)
    assert (
        check('      <input_manager name="IM" version="2"><driver>X_drv</driver></input_manager>\n')
        == []
    )


def test_newer_version_than_known(check):
    (found,) = check('      <tracker name="T" version="7"/>\n')
    assert found.code == "CFG013" and "7" in found.message


def test_missing_or_garbled_version(check):
    assert codes(check('      <tracker name="T"/>\n')) == ["CFG014"]
    assert codes(check('      <tracker name="T" version="one"/>\n')) == ["CFG014"]


def test_element_without_a_name(check):
    assert codes(check('      <tracker version="1"/>\n')) == ["CFG015"]
    assert codes(check('      <tracker name=" " version="1"/>\n')) == ["CFG015"]


# -- properties and values ------------------------------------------------------------


def test_unknown_property_with_close_names(check):
    (found,) = check(tracker("         <baud_rate>9600</baud_rate>\n"))
    assert found.code == "CFG020" and found.line == 6 and "baud_rate" in found.message
    assert "baud" in found.hint
    assert check(tracker("         <baud>9600</baud>\n")) == []


def test_property_dropped_by_a_parents_newer_version(check):
    (found,) = check(tracker("         <device_host>node1</device_host>\n"))
    assert found.code == "CFG021" and found.severity is Severity.WARNING
    assert "input_device version 1" in found.message


def test_property_only_a_newer_version_has(check):
    found = check('      <gizmo name="G" version="2"><extent>3</extent></gizmo>\n')
    assert "CFG022" in codes(found)
    (newer,) = [d for d in found if d.code == "CFG022"]
    assert "version 3 added it" in newer.message and 'version="3"' in newer.hint
    assert "CFG022" not in codes(
        check('      <gizmo name="G" version="3"><extent>3</extent></gizmo>\n')
    )


def test_more_values_than_slots(check):
    body = "".join("         <offset>0.0</offset>\n" for _ in range(4))
    (found,) = check(tracker(body))
    assert found.code == "CFG023" and found.line == 9  # the fourth value
    assert check(tracker(body.replace("         <offset>0.0</offset>\n", "", 1))) == []


def test_fewer_values_than_slots_names_the_defaults(check):
    (found,) = check(tracker("         <offset>0.5</offset>\n"))
    assert found.code == "CFG024" and found.severity is Severity.INFO
    assert "Y = '0.0'" in found.message and "Z = '1.5'" in found.message
    assert check(tracker("")) == []  # not written at all: defaults, as intended


@pytest.mark.parametrize(
    ("text", "reads"), [("", "0"), ("quick", "0"), ("1.5", "1"), ("12abc", "12")]
)
def test_integer_that_does_not_parse(check, text, reads):
    found = check(tracker(f"         <mode>{text}</mode>\n"))
    assert codes(found) == ["CFG025"]
    if reads is not None:
        assert f"reads it as {reads}" in found[0].message


def test_empty_integer_is_read_as_zero_not_the_default(check):
    (found,) = check(tracker("         <baud />\n"))
    assert found.code == "CFG025" and "reads it as 0" in found.message and "9600" in found.hint


def test_float_values(check):
    assert codes(check(tracker("         <rate>fast</rate>\n"))) == ["CFG025"]
    assert check(tracker("         <rate> 1e3 </rate>\n")) == []
    assert check(tracker("         <rate>-.5</rate>\n")) == []


@pytest.mark.parametrize("text", ["False", "TRUE", "yes", ""])
def test_boolean_spellings(check, text):
    (found,) = check(tracker(f"         <enabled>{text}</enabled>\n"))
    assert found.code == "CFG026" and found.severity is Severity.WARNING
    assert "as true" in found.message


@pytest.mark.parametrize("text", ["true", "false", "1", "0", " false "])
def test_boolean_spellings_accepted(check, text):
    assert check(tracker(f"         <enabled>{text}</enabled>\n")) == []


def test_enumeration_label_in_the_wrong_case(check):
    (found,) = check(tracker("         <units>feet</units>\n"))
    assert found.code == "CFG027" and "'Feet'" in found.hint and "0.0" in found.message
    assert check(tracker("         <units>Feet</units>\n")) == []
    assert check(tracker("         <units>0.3048</units>\n")) == []  # a raw value of the list


def test_value_outside_a_fixed_enumeration(check):
    (found,) = check(tracker("         <baud>4800</baud>\n"))
    assert found.code == "CFG028" and "Slow (1200)" in found.hint and "Fast (9600)" in found.hint
    assert check(tracker("         <baud>Fast</baud>\n")) == []
    assert check(tracker("         <mode>7</mode>\n")) == []  # editable enumeration


def test_value_of_the_wrong_kind(check):
    found = check(tracker("         <position_filters>filter</position_filters>\n"))
    assert codes(found) == ["CFG029"]
    found = check(
        '      <alias name="A" version="1"><proxy><tracker name="x" version="1"/></proxy></alias>\n'
    )
    assert "CFG029" in codes(found)


# -- embedded elements and pointers ----------------------------------------------------


def test_embedded_element_of_a_type_not_allowed(check):
    bad = tracker(
        '         <position_filters><other_filter name="F" version="1"/></position_filters>\n'
    )
    (found,) = check(bad)
    assert found.code == "CFG030" and "position_transform_filter" in found.message
    good = tracker(
        '         <position_filters><scaled_filter name="F" version="1"/></position_filters>\n'
    )
    assert check(good) == []  # derived from an allowed type


def test_embedded_elements_are_checked_too(check):
    body = '         <position_filters><position_transform_filter name="F" version="1"><custom_scale>big</custom_scale></position_transform_filter></position_filters>\n'
    (found,) = check(tracker(body))
    assert found.code == "CFG025" and "Tracker/position_filters/F" in found.message


PROXY = '      <position_proxy name="Head" version="1"><device>{target}</device></position_proxy>\n'


def test_pointer_to_no_element(check):
    (found,) = check(PROXY.format(target="Trakcer") + tracker(""))
    assert found.code == "CFG031" and found.severity is Severity.WARNING
    assert "--together" in found.message and "'Tracker'" in found.hint
    assert check(PROXY.format(target="Tracker") + tracker("")) == []


def test_pointer_checks_span_files_given_together(check):
    files = {
        "a.jconf": configuration(PROXY.format(target="Tracker")),
        "b.jconf": configuration(tracker("")),
    }
    assert codes(check(files=files)) == ["CFG031"]
    assert check(files=files, together=True) == []
    files["b.jconf"] = configuration("")
    (found,) = check(files=files, together=True)
    assert found.code == "CFG031" and found.severity is Severity.ERROR
    assert "no element of the configuration" in found.message


def test_included_file_is_checked_within_the_file_that_includes_it(check):
    files = {
        "main.jconf": configuration(tracker(""), includes=("proxies.jconf",)),
        "proxies.jconf": configuration(PROXY.format(target="Tracker")),
    }
    assert check(files=files) == []  # both given: proxies.jconf is judged as part of main.jconf
    assert codes(check(files=files, only=("proxies.jconf",))) == ["CFG031"]


def test_pointer_to_an_element_of_a_type_not_allowed(check):
    found = check(PROXY.format(target="Box") + '      <cmd_box name="Box" version="1"/>\n')
    assert codes(found) == ["CFG032"]
    assert "positional_device" in found[0].message


def test_required_pointer_empty_or_missing(check):
    (found,) = check('      <position_proxy name="Head" version="1"><device/></position_proxy>\n')
    assert found.code == "CFG033" and "is empty" in found.message
    (found,) = check('      <alias name="A" version="1"/>\n')
    assert found.code == "CFG033" and "is not set" in found.message
    found = check('      <simulated_digital_device name="S" version="1"/>\n')
    assert codes(found) == ["CFG033"] and "never sees a key" in found[0].message


def test_duplicate_names_same_file_and_across_files(check):
    found = check(tracker("") + tracker(""))
    # a warning since issue 17 (only duplicates within one file or unrelated files warn)
    assert (
        codes(found) == ["CFG040"] and found[0].severity is Severity.WARNING and found[0].line == 7
    )
    files = {
        "main.jconf": configuration(tracker(""), includes=("base.jconf",)),
        "base.jconf": configuration(tracker("")),
    }
    # an including file overriding its include: info (issue 17), see test_config_checks_round2
    (found,) = check(files=files, only=("main.jconf",), categories=(Category.CONFIG,))
    assert found.code == "CFG042" and found.severity is Severity.INFO
    assert found.path.endswith("main.jconf") and "base.jconf" in found.message
    assert check(tracker("") + tracker("").replace('"Tracker"', '"Tracker 2"')) == []


# -- pending -------------------------------------------------------------------------


def test_command_proxy_waits_for_its_device_and_the_alias_for_the_proxy(check):
    elements = (
        '      <alias name="Cmd" version="1"><proxy>CmdProxy</proxy></alias>\n'
        '      <command_proxy name="CmdProxy" version="1"><device>Box</device></command_proxy>\n'
    )
    found = check(elements)
    assert codes(found) == ["CFG041", "CFG031"]  # in line order: the alias comes first
    pending, missing = found
    assert "pending forever" in missing.message
    assert "alias 'Cmd' would stay pending" in pending.message and "CmdProxy" in pending.message
    assert pending.severity is Severity.WARNING  # the root cause may come from another file
    (pending,) = [
        d
        for d in check(elements, files={"t.jconf": configuration(elements)}, together=True)
        if d.code == "CFG041"
    ]
    assert pending.severity is Severity.ERROR
    assert check(elements + '      <cmd_box name="Box" version="1"/>\n') == []


def test_stupefied_proxy_does_not_wait(check):
    found = check(
        '      <alias name="Head" version="1"><proxy>HeadProxy</proxy></alias>\n'
        + PROXY.format(target="Nothing").replace('"Head"', '"HeadProxy"')
    )
    assert codes(found) == ["CFG031"]
    assert "returns default data" in found[0].message


def test_refused_old_version_stays_pending(check):
    found = check(
        '      <input_manager name="IM" version="1"><driver>X_drv</driver></input_manager>\n'
    )
    (pending,) = [d for d in found if d.code == "CFG041"]
    assert "older than version 2" in pending.message and pending.severity is Severity.ERROR


def test_gesture_proxy_is_never_handled(check):
    found = check(
        '      <gesture_proxy name="G" version="1"><device>Box</device></gesture_proxy>\n'
        '      <cmd_box name="Box" version="1"/>\n'
    )
    assert codes(found) == ["CFG041"] and found[0].severity is Severity.WARNING


def test_pointer_to_an_embedded_element_never_satisfies_a_dependency(check):
    elements = (
        '      <holder name="H" version="1"><parts><cmd_box name="Inner" version="1"/></parts></holder>\n'
        '      <holder name="User" version="1"><target>H/parts/Inner</target></holder>\n'
    )
    (found,) = check(elements)
    assert found.code == "CFG041" and "embedded" in found.message


# -- environment variables and definition paths --------------------------------------


def test_undefined_variable_in_driver_path(check):
    elements = (
        '      <input_manager name="IM" version="2"><driver_path>${DRIVERS}/lib</driver_path>'
        "</input_manager>\n"
    )
    (found,) = check(elements)
    assert found.code == "CFG003" and "DRIVERS" in found.message
    assert check(elements, environ={"DRIVERS": "/opt"}) == []


def test_undefined_variable_in_an_include(check):
    files = {"main.jconf": configuration("", includes=("${CFG}/base.jconf",))}
    assert codes(check(files=files)) == ["CFG001", "CFG003"]


def test_definition_path_is_resolved_against_the_configuration_directory(tmp_path, check):
    from config_samples import definition, prop, version

    write(
        tmp_path / "conf" / "mydefs" / "widget.jdef",
        definition("widget", version(1, prop("size", "integer"))),
    )
    text = configuration(
        '      <widget name="W" version="1"><size>3</size></widget>\n', definition_path=("mydefs",)
    )
    assert check(files={"conf/w.jconf": text}) == []
    text = configuration(
        '      <widget name="W" version="1"/>\n', definition_path=("nowhere", "${NODEFS}")
    )
    found = check(files={"conf/w.jconf": text}, categories=(Category.CONFIG, Category.DEFINITION))
    # the unset variable expands to nothing, i.e. the configuration's own directory
    assert sorted(codes(found)) == ["CFG003", "CFG010", "DEF023"]


def test_findings_are_not_repeated_for_a_file_included_twice(check):
    files = {
        "a.jconf": configuration("", includes=("shared.jconf",)),
        "b.jconf": configuration("", includes=("shared.jconf",)),
        "shared.jconf": configuration(tracker("         <rate>x</rate>\n")),
    }
    assert codes(check(files=files)) == ["CFG025"]


def test_include_cycle_and_missing_include(check):
    files = {
        "a.jconf": configuration(tracker(""), includes=("b.jconf",)),
        "b.jconf": configuration("", includes=("a.jconf", "nowhere.jconf")),
    }
    found = check(files=files, only=("a.jconf",))
    assert sorted(codes(found)) == ["CFG001", "CFG002"]


def test_pre_commit_hook_definition():
    from conftest import REPO

    text = (REPO / ".pre-commit-hooks.yaml").read_text(encoding="utf-8")
    assert "- id: gadgetctl-validate" in text
    assert "entry: gadgetctl validate" in text and "language: python" in text
    assert r"files: \.(jconf|jdef)$" in text


def test_values_on_one_line_get_their_own_columns(check):
    line = "         " + "<offset>0.0</offset>" * 4 + "\n"
    (found,) = check(tracker(line))
    assert found.code == "CFG023" and (found.line, found.column) == (
        6,
        10 + 3 * len("<offset>0.0</offset>"),
    )
