"""Issue 2 acceptance: XML- and schema-level findings on the real VR Juggler corpus."""

from __future__ import annotations

import json
from pathlib import Path

from gadgetctl.validate import validate_paths

# (file relative to the corpus, code, line) of every XML/schema-level finding expected.
EXPECTED = {
    ("modules/vrjuggler/data/configFiles/example.dtrack.jconf", "XML011", 2),
    ("modules/vrjuggler/data/configFiles/example.dtrack.jconf", "XML012", 3),
    ("modules/vrjuggler/data/configFiles/example.sdl_joystick.jconf", "XML012", 3),
    ("modules/vrjuggler/data/configFiles/example.sdl_joystick.jconf", "SCH001", 3),
    ("modules/vrjuggler/data/definitions/flock.jdef", "XML002", 114),
    ("modules/vrjuggler/samples/OGL/simple/ConfigApp/config_app.jdef", "XML013", 3),
    ("modules/jackal/test/TestSuite/TestFiles/definitions/ptr_to_child_elt.jdef", "SCH001", 7),
    ("modules/jackal/test/TestSuite/TestFiles/definitions/dep_test_element.jdef", "SCH001", 3),
    ("modules/jackal/test/TestSuite/TestFiles/definitions/dep_test_element.jdef", "SCH001", 9),
    ("modules/jackal/test/TestSuite/TestFiles/definitions/dep_test_element.jdef", "SCH001", 13),
    ("modules/jackal/test/TestSuite/TestFiles/definitions/dep_test_element.jdef", "SCH001", 17),
}


def _xml_and_schema(result, corpus):
    return {
        (str(Path(d.path).relative_to(corpus)), d.code, d.line)
        for d in result.diagnostics
        if d.category.value in ("xml", "schema")
    }


def test_exactly_the_six_broken_files_have_xml_or_schema_findings(corpus):
    result = validate_paths([corpus])
    assert (
        len(result.files) == 236
    )  # every .jdef and .jconf; the two .xsd files are not JCCL documents
    assert _xml_and_schema(result, corpus) == EXPECTED
    assert len({f for f, _, _ in EXPECTED}) == 6


def test_flock_bad_byte_position_and_latin1_fallback(corpus):
    flock = corpus / "modules/vrjuggler/data/definitions/flock.jdef"
    result = validate_paths([flock])
    (bad,) = [d for d in result.diagnostics if d.code == "XML002"]
    line = flock.read_bytes().split(b"\n")[113]
    assert (bad.line, bad.column) == (114, line.index(b"\xae") + 1)
    assert "0xAE" in bad.message
    # the Latin-1 reading went on: no parse error, and definition checks ran on the file
    assert not [d for d in result.diagnostics if d.code == "XML001"]


def test_schema_finding_names_element_path_and_column(corpus):
    path = corpus / "modules/jackal/test/TestSuite/TestFiles/definitions/ptr_to_child_elt.jdef"
    (finding,) = [d for d in validate_paths([path]).diagnostics if d.code == "SCH001"]
    assert finding.message.startswith("/definition/definition_version/property:")
    assert "value" in finding.message
    assert finding.column == path.read_text().splitlines()[6].index("<property") + 1


def test_cli_json_on_corpus(cli, corpus):
    result = cli("validate", corpus, "--format", "json")
    assert result.exit_code == 1
    data = json.loads(result.stdout)
    assert {"code", "severity", "category", "path", "line", "column", "message", "hint"} == set(
        data[0]
    )
    assert {d["path"] for d in data if d["category"] in ("xml", "schema")} == {
        str(corpus / f) for f, _, _ in EXPECTED
    }
