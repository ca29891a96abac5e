"""`gadgetctl upgrade`: element upgrades through the definitions' transforms, file formats,
byte-for-byte preservation, and the command's modes (issue 4, item 5)."""

from __future__ import annotations

import pytest

from gadgetctl.jccl.repository import default_repository
from gadgetctl.jccl.upgrade import upgrade_bytes

from config_samples import CONFIG_NS, configuration, definition, prop, version, write_definitions
from conftest import CORPUS_DEFINITIONS, write

OLD_WINDOW = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="old window">
   <!-- a window written for display_window version 2 -->
   <elements>
      <display_window name="Main Window" version="2">
         <origin>10</origin>
         <origin>20</origin>
         <size>640</size>
         <size>480</size>
         <pipe>0</pipe>
         <stereo>false</stereo>
         <border>true</border>
         <act_as_event_source>false</act_as_event_source>
         <active>true</active>
      </display_window>
      <alias name="Untouched" version="1">
         <proxy >Somewhere</proxy>
      </alias>
   </elements>
</configuration>
"""

# v3 adds hide_mouse; v4 keeps the listed properties, drops act_as_event_source and adds
# keyboard_mouse_device_name; v5 adds full_screen and always_on_top; v6 allow_mouse_locking.
UPGRADED_WINDOW = """      <display_window name="Main Window" version="6">
         <origin>10</origin>
         <origin>20</origin>
         <size>640</size>
         <size>480</size>
         <pipe>0</pipe>
         <stereo>false</stereo>
         <border>true</border>
         <hide_mouse>false</hide_mouse>
         <active>true</active>
         <keyboard_mouse_device_name/>
         <full_screen>false</full_screen>
         <always_on_top>false</always_on_top>
         <allow_mouse_locking>true</allow_mouse_locking>
      </display_window>"""


@pytest.mark.parametrize(
    "bundled", [False, True], ids=["corpus definitions", "bundled definitions"]
)
def test_display_window_version_2_upgrades_in_four_steps(tmp_path, bundled):
    repo = default_repository([] if bundled else [CORPUS_DEFINITIONS], bundled=bundled)
    result = upgrade_bytes(tmp_path / "w.jconf", OLD_WINDOW.encode(), repo)
    assert not result.problems
    start = OLD_WINDOW.index("      <display_window")
    end = OLD_WINDOW.index("</display_window>") + len("</display_window>")
    assert result.upgraded.decode() == OLD_WINDOW[:start] + UPGRADED_WINDOW + OLD_WINDOW[end:]
    (step,) = result.elements
    assert (step.type, step.name, step.from_version, step.to_version, step.line) == (
        "display_window",
        "Main Window",
        2,
        6,
        6,
    )


@pytest.fixture
def repo(tmp_path):
    return default_repository([write_definitions(tmp_path / "defs")], bundled=False)


def test_new_elements_from_a_transform_follow_the_upgraded_one(tmp_path, repo):
    text = configuration(
        '      <gizmo name="G" version="1">\n         <size>4</size>\n      </gizmo>\n'
        '      <tracker name="T" version="1"/>\n'
    )
    result = upgrade_bytes(tmp_path / "g.jconf", text.encode(), repo)
    assert not result.problems
    assert result.upgraded.decode() == text.replace(
        '      <gizmo name="G" version="1">\n         <size>4</size>\n      </gizmo>\n',
        '      <gizmo name="G" version="3">\n         <extent>4</extent>\n         <color>red</color>\n'
        '      </gizmo>\n      <gizmo_label name="G label" version="1"/>\n',
    )
    (step,) = result.elements
    assert (step.from_version, step.to_version, step.created) == (1, 3, 1)


def test_embedded_elements_are_upgraded_in_place(tmp_path, repo):
    text = configuration(
        '      <holder name="H" version="1">\n         <parts>\n'
        '            <input_manager name="IM" version="1"><driver>A_drv</driver></input_manager>\n'
        "         </parts>\n      </holder>\n"
    )
    result = upgrade_bytes(tmp_path / "h.jconf", text.encode(), repo)
    assert '<input_manager name="IM" version="2">' in result.upgraded.decode()
    assert result.upgraded.decode().startswith(text[: text.index("<input_manager")])


def test_a_failing_element_leaves_the_file_unchanged(tmp_path, repo):
    broken = definition("gizmo", version(1, prop("size")), version(2, prop("size")))  # no transform
    write(tmp_path / "defs" / "gizmo.jdef", broken)
    repo = default_repository([tmp_path / "defs"], bundled=False)
    text = configuration(
        '      <gizmo name="G" version="1"/>\n      <input_manager name="IM" version="1"/>\n'
    )
    result = upgrade_bytes(tmp_path / "g.jconf", text.encode(), repo)
    assert result.upgraded is None and not result.changed
    (problem,) = result.problems
    assert (
        problem.code == "CFG050" and "no upgrade transform" in problem.message and problem.line == 5
    )


def test_stylesheets_cannot_read_files(tmp_path):
    secret = write(tmp_path / "secret.xml", "<secret>42</secret>")
    sheet = (
        '<xsl:stylesheet xmlns:xsl="http://www.w3.org/1999/XSL/Transform" version="1.0">'
        '<xsl:template match="/"><xsl:element name="gizmo" namespace="' + CONFIG_NS + '">'
        f'<xsl:attribute name="version">2</xsl:attribute><xsl:value-of select="document(\'{secret.as_uri()}\')"/>'
        "</xsl:element></xsl:template></xsl:stylesheet>"
    )
    write(
        tmp_path / "defs" / "gizmo.jdef",
        definition("gizmo", version(1), version(2, transform=sheet)),
    )
    repo = default_repository([tmp_path / "defs"], bundled=False)
    result = upgrade_bytes(
        tmp_path / "g.jconf", configuration('      <gizmo name="G" version="1"/>\n').encode(), repo
    )
    assert result.upgraded is None
    assert result.problems and result.problems[0].code == "CFG050"


def test_configuration_namespace_and_processing_instruction(tmp_path, repo):
    text = (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<?org-vrjuggler-jccl-settings configuration.version="3.1"?>\n'
        '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.1/configuration" name="x">\n'
        "   <elements/>\n</configuration>\n"
    )
    result = upgrade_bytes(tmp_path / "x.jconf", text.encode(), repo)
    assert result.upgraded.decode() == text.replace("3.1", "3.0")
    bare = '<?xml version="1.0"?>\n<configuration name="x">\n   <elements>\n     <tracker xmlns="" name="T" version="1"/>\n   </elements>\n</configuration>\n'
    upgraded = upgrade_bytes(tmp_path / "y.jconf", bare.encode(), repo).upgraded.decode()
    assert upgraded == (
        '<?xml version="1.0"?>\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
        f'<configuration xmlns="{CONFIG_NS}" name="x">\n   <elements>\n'
        '     <tracker name="T" version="1"/>\n   </elements>\n</configuration>\n'
    )


def test_definition_format_3_0(tmp_path, repo):
    text = (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<?org-vrjuggler-jccl-settings definition.version="3.0"?>\n'
        '<definition xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/definition" name="d">\n'
        '   <definition_version version="1" label="D">\n      <help>h</help>\n      <parent/>\n'
        "      <upgrade_transform/>\n   </definition_version>\n</definition>\n"
    )
    result = upgrade_bytes(tmp_path / "d.jdef", text.encode(), repo)
    assert result.upgraded.decode() == (
        text.replace("3.0", "3.1").replace(
            'label="D">\n', 'label="D">\n      <abstract>false</abstract>\n'
        )
    )


def test_up_to_date_file_is_unchanged(tmp_path, repo):
    text = configuration('      <tracker name="T" version="1"/>\n')
    result = upgrade_bytes(tmp_path / "t.jconf", text.encode(), repo)
    assert not result.changed and not result.problems


# -- the command ---------------------------------------------------------------------


@pytest.fixture
def old_file(tmp_path):
    return write(tmp_path / "w.jconf", OLD_WINDOW)


def no_bundled(path):
    return ("--no-bundled", "-d", CORPUS_DEFINITIONS, path)


def test_check_exits_1_and_lists_the_elements(cli, old_file):
    result = cli("upgrade", "--check", *no_bundled(old_file))
    assert result.exit_code == 1
    assert "w.jconf:6: display_window 'Main Window': version 2 -> 6" in result.stdout
    assert old_file.read_text() == OLD_WINDOW
    current = write(old_file.parent / "ok.jconf", configuration(""))
    assert cli("upgrade", "--check", *no_bundled(current)).exit_code == 0


def test_check_json(cli, old_file):
    import json

    result = cli("upgrade", "--check", "--format", "json", *no_bundled(old_file))
    (entry,) = json.loads(result.stdout)
    assert entry["elements"][0]["from"] == 2 and entry["elements"][0]["to"] == 6


def test_diff_prints_a_unified_diff(cli, old_file):
    result = cli("upgrade", "--diff", *no_bundled(old_file))
    assert result.exit_code == 0
    assert '-      <display_window name="Main Window" version="2">' in result.stdout
    assert "+         <allow_mouse_locking>true</allow_mouse_locking>" in result.stdout


def test_in_place_keeps_a_backup(cli, old_file):
    result = cli("upgrade", "--in-place", *no_bundled(old_file))
    assert result.exit_code == 0
    assert 'version="6"' in old_file.read_text()
    assert old_file.with_name("w.jconf.bak").read_text() == OLD_WINDOW
    write(old_file, OLD_WINDOW)
    old_file.with_name("w.jconf.bak").unlink()
    assert cli("upgrade", "--in-place", "--no-backup", *no_bundled(old_file)).exit_code == 0
    assert not old_file.with_name("w.jconf.bak").exists()


def test_output_file_and_stdout(cli, old_file, tmp_path):
    out = tmp_path / "new.jconf"
    assert cli("upgrade", "-o", out, *no_bundled(old_file)).exit_code == 0
    assert 'version="6"' in out.read_text() and old_file.read_text() == OLD_WINDOW
    result = cli("upgrade", *no_bundled(old_file))
    assert result.stdout == out.read_text()


def test_usage_errors(cli, old_file, tmp_path):
    other = write(tmp_path / "other.jconf", OLD_WINDOW)
    result = cli("upgrade", old_file, other)
    assert result.exit_code == 2 and "--check" in result.stderr
    assert cli("upgrade", "-o", tmp_path / "x", old_file, other).exit_code == 2
