"""Work `validate` does once, or only when a finding needs it (issue 27 goal 4): the results
must be those of doing it every time, eagerly."""

from __future__ import annotations

import random
import re
from pathlib import Path

import pytest
from lxml import etree

from gadgetctl.jccl import configload, xmlload
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.xmlload import FileKind, SourceLines
from gadgetctl.validate import (
    ValidateOptions,
    plugin_definition_finder,
    plugin_name_finder,
    validate_paths,
)

from conftest import CORPUS, write
from jccl_samples import jconf, jdef, prop

# -- line index ------------------------------------------------------------------------


def _texts(seed: int) -> list[str]:
    rng = random.Random(seed)
    pieces = ["a", "bc", "\n", "\n", "\n\n", "é", "\r", "\r\n", "\u2028", "\x0c", " "]
    plain = ["ab", "\n", "\n\n", "é€", "  "]
    texts = ["", "\n", "a", "a\n", "\na", "\r\n", "a\r\nb\n"]
    for i in range(400):
        choices = pieces if i % 2 else plain  # half with \n only (the split path)
        texts.append("".join(rng.choice(choices) for _ in range(rng.randint(0, 60))))
    return texts


@pytest.mark.parametrize("chunk", [1, 3, 7, 1 << 20])
def test_source_lines_are_those_of_splitlines(monkeypatch, chunk):
    monkeypatch.setattr(xmlload, "_SPLIT_CHUNK", chunk)  # \n on every side of a chunk's edge
    for text in _texts(chunk):
        lines = SourceLines(text)
        assert len(lines) == len(text.splitlines()), repr(text)
        assert [lines[i] for i in range(len(lines))] == text.splitlines(), repr(text)
        if len(lines):
            assert lines[-1] == text.splitlines()[-1]


# -- which configurations are read while parsed --------------------------------------

# The rule as one search of the file as written (what _needs_whole_tree answered before it
# searched the file without white space): every file it flags must still be parsed whole.
_WRITTEN_RULE = re.compile(
    rb"<!DOCTYPE"
    rb"|(?:/>|</[^>]*>|-->|\?>|]]>)[ \t\r\n]*[^ \t\r\n<]"
    rb"|[^ \t\r\n>][ \t\r\n]*<(?:[A-Za-z_:]|!--|!\[|\?)",
    re.IGNORECASE,
)

HEAD = (
    b'<?xml version="1.0"?>\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    b'<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="t">\n'
    b"<elements>\n"
)
TAIL = b"</elements>\n</configuration>\n"
PARTS = [
    b'<alias name="A" version="1">',
    b"<proxy>P</proxy>",
    b"</alias>",
    b"<proxy/>",
    b"<!-- note -->",
    b"<?pi x?>",
    b"<![CDATA[x]]>",
    b"8",
    b"text",
    b" ",
    b"\n  ",
    b"\t",
    b"<a:b>x</a:b>",
    b"</proxy >",
]


def _bodies(count: int) -> list[bytes]:
    rng = random.Random(27)
    return [b"".join(rng.choice(PARTS) for _ in range(rng.randint(1, 8))) for _ in range(count)]


def test_every_file_the_written_rule_flags_is_parsed_whole():
    flagged = 0
    for body in _bodies(3000):
        data = HEAD + body + TAIL
        if _WRITTEN_RULE.search(data):
            flagged += 1
            assert configload._needs_whole_tree(data), data
    assert flagged > 1000  # the cases cover each kind of stray text


@pytest.mark.parametrize(
    "body",
    [
        b"<alias name='A'><proxy>P</proxy></alias> 8 ",  # after an end tag
        b"<alias name='A'><proxy/>  x</alias>",  # after a self-closing tag
        b"<alias name='A'><!-- c -->\n x<proxy>P</proxy></alias>",  # after a comment
        b"<alias name='A'><?pi?>x<proxy>P</proxy></alias>",  # after a PI
        b"<alias name='A'>x\n  <proxy>P</proxy></alias>",  # before a start tag
        b"<alias name='A'>x <!-- c --><proxy>P</proxy></alias>",  # before a comment
    ],
)
def test_stray_text_is_parsed_whole(body):
    assert configload._needs_whole_tree(HEAD + body + TAIL)


def test_a_usual_configuration_is_read_while_parsed():
    body = b'<alias name="A" version="1">\n  <proxy>P</proxy>\n</alias>\n<!-- c -->\n'
    assert not configload._needs_whole_tree(HEAD + body + TAIL)


def _written_needs_whole_tree(data: bytes) -> bool:
    """The whole rule as it was with the one search of the file as written."""
    if _WRITTEN_RULE.search(data):
        return True
    elements = configload._ELEMENTS_TAG.search(data)
    if elements is None:
        return True
    if data.find(configload._XSI, elements.start()) >= 0:
        return True
    for prefix in set(configload._XSI_PREFIX.findall(data)):
        attribute = re.compile(rb"[ \t\r\n]" + re.escape(prefix) + rb":[\w.-]+[ \t\r\n]*=")
        if attribute.search(data, elements.start()):
            return True
    return False


def test_the_corpus_is_split_as_the_written_rule_splits_it():
    for path in sorted(CORPUS.rglob("*.jconf")):
        data = path.read_bytes()
        assert configload._needs_whole_tree(data) == _written_needs_whole_tree(data), path


# -- the settings PI's position, looked up for a finding only -------------------------


def test_a_wrong_format_version_is_placed_at_the_processing_instruction(tmp_path):
    text = jconf().replace('configuration.version="3.0"', 'configuration.version="2.9"')
    text = text.replace("<?org", "  <?org", 1)
    (diag,) = validate_paths([write(tmp_path / "v.jconf", text)]).diagnostics
    assert (diag.code, diag.line, diag.column) == ("XML011", 2, 3)


def test_a_missing_version_key_is_placed_at_the_processing_instruction(tmp_path):
    text = jconf().replace('configuration.version="3.0"', 'other="1"')
    (diag,) = validate_paths([write(tmp_path / "k.jconf", text)]).diagnostics
    assert (diag.code, diag.line, diag.column) == ("XML011", 2, 1)
    assert "no configuration.version" in diag.message


# -- one driver search per run -------------------------------------------------------


def test_the_plugin_finders_share_one_search(tmp_path):
    path = write(tmp_path / "c.jconf", jconf())
    config = load_configuration([path], environ={})
    searches: dict = {}
    dirs = plugin_definition_finder({}, searches)(config)
    assert len(searches) == 1
    (search,) = searches.values()
    names = plugin_name_finder({}, searches)(config)
    assert list(searches.values()) == [search]  # the same search answered both
    assert dirs == search.definition_dirs()
    assert names == {p.name for p in search.plugins() if p.shadowed_by is None}


def test_validate_keeps_the_searches_it_is_given(tmp_path):
    path = write(tmp_path / "c.jconf", jconf())
    searches: dict = {}
    validate_paths([path], ValidateOptions(environ={}, driver_searches=searches))
    assert len(searches) == 1


def test_a_plugin_finder_without_shared_searches_still_answers(tmp_path):
    from gadgetctl.input.definitions import driver_definition_dirs

    config = load_configuration([write(tmp_path / "c.jconf", jconf())], environ={})
    assert plugin_definition_finder({})(config) == driver_definition_dirs(
        configuration=config, environ={}
    )


# -- where a given definition's parts are, looked up when asked ----------------------


def test_definition_locations_are_looked_up_when_asked(tmp_path):
    from gadgetctl.jccl.defparser import read_definition
    from gadgetctl.jccl.xmlload import load_file

    text = jdef("thing", prop("a") + prop("b")).replace("<property ", "  <property ", 1)
    doc = load_file(write(tmp_path / "thing.jdef", text))
    definition = read_definition(doc)
    assert doc._lines is None  # no line of the file was indexed for reading it
    version = definition.newest
    nodes = doc.root.xpath("//*[local-name()='property']")
    for prop_definition, node in zip(version.properties, nodes, strict=True):
        where = prop_definition.location
        assert (where.path, where.line, where.column) == (doc.path, *doc.locate(node))
    assert version.properties[0].location.column == version.properties[1].location.column + 2
    plain = read_definition(load_file(tmp_path / "thing.jdef"), columns=False)
    assert plain.newest.properties[0].location.column is None


def test_a_definition_finding_has_its_column(tmp_path):
    text = jdef("thing", prop("a", "integer", values='<value label="v" defaultvalue="x"/>'))
    text = text.replace("<property ", "   <property ", 1)
    (diag,) = [
        d
        for d in validate_paths([write(tmp_path / "t.jdef", text)]).diagnostics
        if d.code == "DEF001"
    ]
    line = text.splitlines()[diag.line - 1]
    assert line[diag.column - 1 :].startswith("<property ")


XSI_HEAD = HEAD.replace(
    b"<configuration ",
    b'<configuration xmlns:xi="http://www.w3.org/2001/XMLSchema-instance" ',
)


def test_an_xsi_attribute_in_elements_is_parsed_whole():
    used = b'<alias name="A" version="1"\n  xi:type="x"><proxy>P</proxy></alias>\n'
    assert configload._needs_whole_tree(XSI_HEAD + used + TAIL)


def test_an_xsi_prefix_declared_and_unused_in_elements_is_read_while_parsed():
    unused = b'<alias name="A" version="1"><proxy>xi:P</proxy></alias>\n'  # text, no attribute
    assert not configload._needs_whole_tree(XSI_HEAD + unused + TAIL)
    assert not configload._needs_whole_tree(XSI_HEAD + b'<alias name="A"/>\n' + TAIL)


# -- a configuration of one chunk: parsed in one call, then read ----------------------


def test_every_corpus_configuration_reads_the_same_in_one_parse():
    from test_streamed_configurations import both_ways, elements

    taken = 0
    for path in sorted(CORPUS.rglob("*.jconf")):
        data = path.read_bytes()
        assert len(data) <= configload.STREAM_CHUNK  # (each takes the one-parse way)
        streamed, whole = both_ways(data, str(path))
        taken += streamed.streamed is not None
        assert [d.to_dict() for d in streamed.diagnostics] == [
            d.to_dict() for d in whole.diagnostics
        ], path
        if whole.root is not None:
            assert elements(streamed) == elements(whole), path
        if streamed.streamed is not None:
            assert etree.tostring(streamed.root) == etree.tostring(_emptied(whole.root)), path
    assert taken >= 50


def _emptied(root):
    """The whole tree with every <elements> child of the root emptied, as streaming leaves it."""
    for node in root:
        if isinstance(node.tag, str) and node.tag.rpartition("}")[2] == "elements":
            del node[:]
    return root


def test_one_parse_and_the_pull_parse_read_the_same(monkeypatch):
    from test_streamed_configurations import elements, one_line_file

    data = one_line_file(40)
    once = configload.parse_configuration(data, "t.jconf", FileKind.CONFIGURATION)
    monkeypatch.setattr(configload, "STREAM_CHUNK", 256)  # the pull parse, many chunks
    pulled = configload.parse_configuration(data, "t.jconf", FileKind.CONFIGURATION)
    assert once.streamed is not None and pulled.streamed is not None
    assert elements(once) == elements(pulled)
    assert [len(b.elements) for b in once.streamed] == [len(b.elements) for b in pulled.streamed]
    assert [b.embedded for b in once.streamed] == [b.embedded for b in pulled.streamed] == [40]
    assert etree.tostring(once.root) == etree.tostring(pulled.root)


def test_definition_texts_are_those_of_every_text_node(tmp_path):
    from gadgetctl.jccl.defparser import read_definition
    from gadgetctl.jccl.xmlload import load_file

    body = prop("a").replace("<help>property a</help>", "<help>\n  one <!-- c -->two </help>")
    body += prop("b").replace("<help>property b</help>", "<help>  <b>bold</b> tail </help>")
    body += prop("c").replace("<help>property c</help>", "<help/>")
    definition = read_definition(load_file(write(tmp_path / "t.jdef", jdef("t", body))))
    assert [p.help for p in definition.newest.properties] == ["one two", "bold tail", ""]


# -- a repository compares a word with its names once --------------------------------


def test_repository_close_names_are_those_of_close_names_and_follow_additions(monkeypatch):
    from gadgetctl import suggest
    from gadgetctl.jccl.definitions import Definition, DefinitionVersion
    from gadgetctl.jccl.repository import DefinitionRepository, default_repository

    repo = default_repository()
    expected = suggest.close_names("positon_proxy", repo.names(), cutoff=0.6)
    assert expected and repo.close_names("positon_proxy") == expected
    calls = []
    monkeypatch.setattr(suggest, "close_names", lambda *a, **k: calls.append(a) or ["remembered?"])
    assert repo.close_names("positon_proxy") == expected and not calls  # asked once
    assert repo.close_names("positon_proxy", cutoff=0.9) == ["remembered?"]  # its own key
    monkeypatch.undo()
    fresh = DefinitionRepository()
    assert fresh.close_names("positon_proxy") == []
    version = DefinitionVersion("position_proxy", 1, "", False, "", (), (), ())
    fresh.add(Definition(name="position_proxy", versions={1: version}))
    assert fresh.close_names("positon_proxy") == ["position_proxy"]  # the addition counts


def test_real_path_text_is_the_resolved_path(tmp_path):
    from gadgetctl.files import real_path, real_path_text

    real = tmp_path / "real"
    real.mkdir()
    (real / "a.jconf").write_text("x")
    (tmp_path / "link").symlink_to(real)
    (real / "b.jconf").symlink_to(real / "a.jconf")
    for given in (
        str(tmp_path / "link" / "a.jconf"),
        str(tmp_path / "link" / "b.jconf"),
        str(tmp_path / "link" / ".." / "real" / "missing.jconf"),
    ):
        assert real_path_text(given) == str(Path(given).resolve()) == str(real_path(given))
    (real / "sub").mkdir()
    (tmp_path / "deep").symlink_to(real / "sub")
    through = str(tmp_path / "deep" / ".." / "a.jconf")  # real/a.jconf, not tmp_path/a.jconf
    assert real_path_text(through) == str(Path(through).resolve()) == str(real / "a.jconf")
    assert real_path(through) == real / "a.jconf"
