"""File-format markers: the settings processing instruction and namespaces."""

from __future__ import annotations

from gadgetctl.validate import validate_paths

from conftest import write
from jccl_samples import CONFIG_NS, jconf, jdef, prop


def found(path):
    return {(d.code, d.line) for d in validate_paths([path]).diagnostics}


def test_clean_configuration_and_definition(tmp_path):
    assert found(write(tmp_path / "ok.jconf", jconf())) == set()
    assert found(write(tmp_path / "ok.jdef", jdef("thing", prop("p")))) == set()


def test_missing_pi_is_a_warning(tmp_path):
    text = jconf().replace('<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n', "")
    (diag,) = validate_paths([write(tmp_path / "nopi.jconf", text)]).diagnostics
    assert (diag.code, diag.severity.value) == ("XML010", "warning")


def test_unknown_configuration_format_version(tmp_path):
    text = jconf().replace('configuration.version="3.0"', 'configuration.version="2.9"')
    assert found(write(tmp_path / "v.jconf", text)) == {("XML011", 2)}


def test_configuration_namespace_31_does_not_exist(tmp_path):
    text = jconf().replace(CONFIG_NS, CONFIG_NS.replace("3.0", "3.1"))
    diags = validate_paths([write(tmp_path / "ns.jconf", text)]).diagnostics
    assert [(d.code, d.line) for d in diags] == [("XML012", 3)]
    assert "no configuration namespace" in diags[0].message


def test_configuration_without_namespace_still_gets_schema_checks(tmp_path):
    text = jconf().replace(f' xmlns="{CONFIG_NS}"', "").replace(' name="test"', "")
    assert found(write(tmp_path / "nons.jconf", text)) == {("XML012", 3), ("SCH001", 3)}


def test_old_definition_format_has_upgrade_hint(tmp_path):
    text = jdef("old", prop("p")).replace("3.1", "3.0")
    (diag,) = validate_paths([write(tmp_path / "old.jdef", text)]).diagnostics
    assert diag.code == "XML013" and "gadgetctl upgrade" in diag.hint
