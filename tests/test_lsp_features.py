"""The language server's features on the library core, in process (no protocol, no pygls):
completion, hover, navigation and fixes for texts as an editor holds them."""

from __future__ import annotations

import pytest
from lsp_samples import DEVICES, HEAD, configuration

from gadgetctl.lsp import actions, completion, hover, navigation
from gadgetctl.lsp.analysis import Engine
from gadgetctl.lsp.syntax import Where, context_at
from gadgetctl.validate import validate_paths

from conftest import CORPUS_CONFIGS

BODY = DEVICES.replace(">Feet<", ">feet<")


@pytest.fixture
def opened(tmp_path):
    def open_(text: str, name: str = "t.jconf"):
        path = tmp_path / name
        path.write_text(text)
        engine = Engine()
        engine.set_text(path, text)
        return engine, path

    return open_


def _labels(model, text: str, offset: int) -> list[str]:
    return [item.label for item in completion.complete(model, text, offset).items]


def test_the_cursor_is_placed_in_half_typed_text():
    text = HEAD + '<elements>\n<position_proxy name="P" version="'
    ctx = context_at(text, len(text))
    assert (ctx.where, ctx.attribute, ctx.tag.name) == (Where.VALUE, "version", "position_proxy")
    ctx = context_at(text + '1"><dev', len(text) + 7)
    assert (ctx.where, ctx.prefix, ctx.parent.name) == (Where.TAG, "dev", "position_proxy")
    commented = HEAD + "<elements><!-- <dtrack> --><"
    assert context_at(commented, len(commented)).parent.name == "elements"


def test_completion_of_types_properties_labels_booleans_and_versions(opened):
    engine, path = opened(BODY)
    model = engine.model(path)
    types = _labels(model, BODY, BODY.index("<dtrack") + 1)
    assert "position_proxy" in types and "dtrack" in types
    assert "proxy" not in types  # abstract
    items = completion.complete(model, BODY, BODY.index("<device>Tracker") + 1).items
    assert items[0].label == "device" or min(items, key=lambda i: i.sort).label == "device"
    assert next(i for i in items if i.label == "device").detail.startswith("required")
    assert "unit" not in [i.label for i in items]  # written already, one value
    # <dtrack> has its receive_port: not offered again; a three-value property is
    written = [
        i.label for i in completion.complete(model, BODY, BODY.index("<position_filters") + 1).items
    ]
    assert "receive_port" not in written and "server_name" in written
    assert "position_filters" in written  # (the one being typed)
    units = _labels(model, BODY, BODY.index(">feet<") + 1)
    assert units == ["Custom", "Meters", "Centimeters", "Feet", "Inches"]
    embedded = _labels(model, BODY, BODY.index("<position_transform_filter") + 1)
    assert "position_transform_filter" in embedded and "dtrack" not in embedded
    versions = BODY.index('version="1">\n         <receive') + len('version="')
    assert _labels(model, BODY, versions) == ["1"]
    aliases = _labels(model, BODY, BODY.index(">Head</proxy>") + 1)
    assert aliases == ["Keys", "Head"]  # proxies; not the devices, not the alias itself


def test_completion_of_include_paths_and_jdef_parents(opened, tmp_path):
    (tmp_path / "devices").mkdir()
    (tmp_path / "devices" / "trackers.jconf").write_text(HEAD + "</configuration>\n")
    text = HEAD + "   <include>dev</include>\n</configuration>\n"
    engine, path = opened(text)
    labels = _labels(engine.model(path), text, text.index("dev</include>") + 3)
    assert labels == ["devices/trackers.jconf"]
    jdef = '<definition name="mine"><definition_version version="1"><parent>pos'
    engine, jpath = opened(jdef, "mine.jdef")
    parents = _labels(engine.model(jpath), jdef, len(jdef))
    assert "positional_device" in parents


def test_hover_tells_whether_an_element_stays_pending_and_why(opened):
    text = BODY.replace("<proxy>Head</proxy>", "<proxy>Nobody</proxy>")
    engine, path = opened(text)
    findings = engine.diagnose(path)
    shown = hover.hover(engine.model(path), text, text.index("<alias") + 2, findings)
    assert "alias" in shown and "stays pending" in shown and "Nobody" in shown
    shown = hover.hover(engine.model(path), BODY, BODY.index("<position_proxy") + 2, [])
    assert "becomes active" in shown
    at_end = hover.hover(engine.model(path), BODY, BODY.index("</position_proxy") + 4, [])
    assert at_end == shown
    unit = hover.hover(engine.model(path), BODY, BODY.index("</unit>") + 3, [])
    assert unit.startswith("**unit** (integer")


def test_references_and_rename_follow_pointers(opened):
    engine, path = opened(BODY)
    model = engine.model(path)
    spots = navigation.references(model, BODY, BODY.index('"Head"') + 2, True)
    assert [BODY[s.start : s.end] for s in spots] == ["Head", "Head"]
    assert spots[1].start == BODY.index(">Head</proxy>") + 1
    edits = navigation.rename(model, BODY, BODY.index(">Head</proxy>") + 2, "HeadProxy")
    assert sorted(s.start for s in edits[path]) == [s.start for s in spots]


def test_go_to_definition_of_a_pointer_and_an_element_type(opened):
    engine, path = opened(BODY)
    model = engine.model(path)
    spot = navigation.definition(model, BODY, BODY.index(">Tracker</device>") + 2)
    assert BODY[spot.start : spot.end] == "Tracker" and spot.start < BODY.index("<position_proxy")
    target = navigation.definition(model, BODY, BODY.index("<dtrack") + 2)
    assert target.path.name == "dtrack.jdef" and target.line


def test_outline_groups_elements_by_type_and_folds_them(opened):
    symbols = navigation.symbols(BODY)
    assert [(s.name, [c.name for c in s.children]) for s in symbols] == [
        ("dtrack", ["Tracker"]),
        ("simulated_analog_device", ["Sliders"]),
        ("keyboard_mouse_proxy", ["Keys"]),
        ("keyboard_mouse_device", ["Keyboard"]),
        ("position_proxy", ["Head"]),
        ("alias", ["VJHead"]),
    ]
    lines = BODY.splitlines()
    first = next(i for i, line in enumerate(lines) if "<dtrack" in line)
    assert (first, first + 7) in navigation.folding(BODY)


def _fix(engine, path, text, code):
    findings = [d for d in engine.diagnose(path) if d.code == code]
    assert findings, f"validate finds {code}"
    from gadgetctl.lsp.findings import findings as ranged
    from gadgetctl.lsp.text import LineIndex

    finding = ranged(findings, LineIndex(text, utf16=False))[0]
    problem = actions.Problem(code, finding.start, finding.end)
    return actions.actions(engine.model(path), text, [problem])


def _apply(text, edits):
    for start, end, new in sorted(edits, reverse=True):
        text = text[:start] + new + text[end:]
    return text


def test_a_label_in_the_wrong_case_is_fixed(opened):
    engine, path = opened(BODY)
    fixes = _fix(engine, path, BODY, "CFG027")
    assert fixes[0].title == "Write 'Feet'"
    fixed = _apply(BODY, fixes[0].edits[path])
    assert fixed == BODY.replace(">feet<", ">Feet<")


def test_a_pointer_naming_nothing_is_fixed_with_the_close_names(opened):
    text = BODY.replace("<proxy>Head</proxy>", "<proxy>head</proxy>")
    engine, path = opened(text)
    (finding,) = [d for d in engine.diagnose(path) if d.code == "CFG031"]
    assert finding.hint == "Did you mean 'Head', 'VJHead'?"
    fixes = _fix(engine, path, text, "CFG031")
    assert [f.title for f in fixes] == ["Did you mean 'Head'?", "Did you mean 'VJHead'?"]
    assert _apply(text, fixes[0].edits[path]) == BODY


def test_a_missing_required_pointer_is_added_in_the_files_indentation(opened):
    text = BODY.replace("         <proxy>Head</proxy>\n", "")
    engine, path = opened(text)
    fixes = _fix(engine, path, text, "CFG033")
    fixed = _apply(text, fixes[0].edits[path])
    assert '<alias name="VJHead" version="1">\n         <proxy></proxy>' in fixed


def test_an_unknown_type_is_renamed_start_and_end_tag(opened):
    text = BODY.replace("position_proxy", "positon_proxy")
    engine, path = opened(text)
    fixes = _fix(engine, path, text, "CFG010")
    assert fixes[0].title == "Did you mean position_proxy?"
    assert _apply(text, fixes[0].edits[path]) == BODY


def test_an_old_element_is_upgraded_in_the_files_own_formatting(opened):
    text = (CORPUS_CONFIGS / "example.vrpn.jconf").read_text()
    engine, path = opened(text)
    fixes = _fix(engine, path, text, "CFG012")
    upgrade = next(f for f in fixes if f.title.startswith("Upgrade"))
    fixed = _apply(text, upgrade.edits[path])
    path.write_text(fixed)
    assert not [d for d in validate_paths([path]).diagnostics if d.code == "CFG012"]
    changed = [a != b for a, b in zip(text.splitlines(), fixed.splitlines(), strict=False)]
    assert sum(changed) <= 3  # the element's start tag and what the step changes, no more


def test_unsaved_text_is_what_validate_reads(opened):
    engine, path = opened(BODY)
    assert not [d for d in engine.diagnose(path) if d.code == "CFG020"]
    engine.set_text(path, BODY.replace("receive_port", "recieve_port"))
    assert [d.code for d in engine.diagnose(path) if d.code == "CFG020"] == ["CFG020"]
    assert path.read_text() == BODY  # nothing written


def test_one_old_element_is_upgraded_alone(opened):
    text = (CORPUS_CONFIGS / "example.vrpn.jconf").read_text()
    start = text.index('      <vrpn name="Vrpn"')
    end = text.index("</vrpn>\n", start) + len("</vrpn>\n")
    second = text[start:end].replace('name="Vrpn"', 'name="Vrpn2"')
    text = text[:end] + second + text[end:]
    engine, path = opened(text)
    fixes = _fix(engine, path, text, "CFG012")
    assert [f.title for f in fixes] == [
        "Upgrade this element",
        "Upgrade the file (gadgetctl upgrade)",
    ]
    fixed = _apply(text, fixes[0].edits[path])
    assert (
        fixed.endswith(text[end:])
        and fixed[end - len(text) :] == second + text[end + len(second) :]
    )
    path.write_text(fixed)
    old = [d for d in validate_paths([path]).diagnostics if d.code == "CFG012"]
    assert [d.line for d in old] == [text[:end].count("\n") + 1]  # only the copy is left


def test_a_definition_file_is_checked_and_its_unsaved_text_judges_configurations(opened, tmp_path):
    defs = tmp_path / "defs"
    defs.mkdir()
    jdef = defs / "probe.jdef"
    definition = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings definition.version="3.1"?>
<definition xmlns="http://www.vrjuggler.org/jccl/xsd/3.1/definition" name="probe">
   <definition_version version="1" label="Probe">
      <abstract>false</abstract>
      <help>A probe.</help>
      <parent>positional_device</parent>
      <category>/Devices</category>
      <property valuetype="integer" variable="false" name="rate">
         <help>Samples a second.</help>
         <value label="Rate" defaultvalue="60"/>
      </property>
      <upgrade_transform/>
   </definition_version>
</definition>
"""
    jdef.write_text(definition)
    config = configuration(
        '      <probe name="P" version="1">\n         <depth>3</depth>\n      </probe>\n',
        before="   <definition_path>\n      <dir>defs</dir>\n   </definition_path>\n",
    )
    engine, path = opened(config)
    assert [d.code for d in engine.diagnose(path) if d.code.startswith("CFG02")] == ["CFG020"]
    types = _labels(engine.model(path), config, config.index("<probe") + 1)
    assert "probe" in types
    edited = definition.replace('name="rate"', 'name="depth"')
    engine.set_text(jdef, edited)
    assert not [d for d in engine.diagnose(path) if d.code.startswith("CFG02")]
    broken = edited.replace("<parent>positional_device</parent>", "<parent>no_such</parent>")
    engine.set_text(jdef, broken)
    assert any(d.code.startswith("DEF") for d in engine.diagnose(jdef))
    assert jdef.read_text() == definition  # nothing written


@pytest.mark.parametrize(
    "shape",
    [
        "<a" + "b" * 300_000,  # a name with no end
        "<a " + 'x="1" ' * 50_000,  # attributes with no end of tag
        "<a " + '="' * 150_000,  # values opened and never closed
        "<" + "a" * 300_000 + "\n",
        "<!--" * 75_000,  # comments never closed
        "<a b" + " " * 300_000,
        "<a>" * 100_000,  # elements nested far past any limit
    ],
)
def test_hostile_lines_are_read_in_linear_time(shape):
    # Each of these made a scan backtrack quadratically (hours at this size); the test's
    # timeout is the guard, nothing here is timed.
    for offset in (len(shape) // 2, len(shape)):
        context_at(shape, offset)
    assert len(navigation.symbols(shape)) <= navigation.MAX_SYMBOLS
    navigation.folding(shape)


def test_the_outline_says_where_it_stops():
    many = configuration("".join(f'<alias name="A{i}" version="1"/>' for i in range(20_005)))
    groups = navigation.symbols(many)
    assert len(groups[0].children) == navigation.MAX_SYMBOLS
    assert groups[-1].name == f"(the outline stops at {navigation.MAX_SYMBOLS} elements)"
