"""Configurations read while they are parsed (issue 26 item 9): `validate` reads the
elements of a configuration a chunk at a time and drops their nodes, so that the lxml tree
of a large file never exists whole. The result must be exactly what reading the whole tree
gives: the same elements, values and positions, the same findings."""

from __future__ import annotations

from pathlib import Path

import pytest
from lxml import etree

from gadgetctl.jccl import configload
from gadgetctl.jccl.configload import parse_configuration, read_config_file
from gadgetctl.jccl.configuration import ConfigElement
from gadgetctl.jccl.xmlload import FileKind, parse_bytes
from gadgetctl.validate import ValidateOptions, validate_paths

from conftest import CORPUS
from jccl_samples import CONFIG_NS

HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    f'<configuration xmlns="{CONFIG_NS}" name="t">\n'
)


def described(element: ConfigElement) -> tuple:
    """Everything a check can read of an element, positions resolved."""
    location = element.location
    return (
        element.type,
        element.name,
        element.version_text,
        (location.path, location.line, location.column),
        [
            (
                name,
                [
                    (
                        value.text,
                        (value.location.line, value.location.column),
                        None if value.element is None else described(value.element),
                    )
                    for value in values
                ],
            )
            for name, values in element.property_items()
        ],
    )


def both_ways(data: bytes, path: str = "t.jconf"):
    streamed = parse_configuration(data, path, FileKind.CONFIGURATION)
    whole = parse_bytes(data, path, FileKind.CONFIGURATION)
    return streamed, whole


def elements(doc) -> list[tuple]:
    config = read_config_file(doc, Path(doc.path))
    return [described(e) for e in config.elements]


def corpus_configurations() -> list[Path]:
    return sorted(CORPUS.rglob("*.jconf"))


def test_every_corpus_configuration_reads_the_same_streamed(corpus, monkeypatch):
    monkeypatch.setattr(configload, "STREAM_CHUNK", 512)  # many chunks even in small files
    streamed_files = 0
    for path in corpus_configurations():
        data = path.read_bytes()
        streamed, whole = both_ways(data, str(path))
        streamed_files += streamed.streamed is not None
        assert [d.to_dict() for d in streamed.diagnostics] == [
            d.to_dict() for d in whole.diagnostics
        ], path
        if whole.root is None:
            assert streamed.root is None, path
            continue
        assert elements(streamed) == elements(whole), path
    assert streamed_files >= 50  # most are read streamed: the test covers that path


def one_line_file(count: int) -> bytes:
    """``count`` proxies, devices and aliases on one line, embedded elements and comments
    among them: positions come from ranks among the tags of one name on a line."""
    parts = []
    for i in range(count):
        parts.append(
            f'<position_proxy name="P{i}" version="1"><device>D{i}</device><unit>0</unit>'
            '<position_filters><position_transform_filter name="f" version="2">'
            "<device_units>Feet</device_units></position_transform_filter></position_filters>"
            f'</position_proxy><!-- {i} --><alias name="A{i}" version="1"><proxy>P{i}</proxy>'
            f'</alias><waveform_device name="D{i}" version="1"><rate>60.0</rate>'
            "</waveform_device>"
        )
    return (HEAD + "<elements>" + "".join(parts) + "</elements></configuration>\n").encode()


def test_a_file_on_one_line_reads_the_same_streamed(monkeypatch):
    monkeypatch.setattr(configload, "STREAM_CHUNK", 300)
    streamed, whole = both_ways(one_line_file(60))
    assert streamed.streamed is not None
    assert elements(streamed) == elements(whole)


def test_the_tree_keeps_no_element_that_was_read(monkeypatch):
    monkeypatch.setattr(configload, "STREAM_CHUNK", 1000)
    streamed, _ = both_ways(one_line_file(200))
    (block,) = streamed.root.iter(f"{{{CONFIG_NS}}}elements")
    assert len(block) == 0  # every element node was dropped once read
    assert sum(len(b.elements) for b in streamed.streamed) == 600


@pytest.mark.parametrize(
    "body",
    [
        # text between elements (XML015), which the schema sees too
        '<elements><alias name="A" version="1"><proxy>P</proxy></alias> 8 </elements>',
        # (and each with a document type: entities are reported from the tree)
        '<elements><alias name="A" version="1"><proxy>P</proxy></alias></elements>',
        # a nested <configuration>, which the schema checks
        '<elements><alias name="A" version="1"><proxy><configuration name="x"/></proxy>'
        "</alias></elements>",
        # a structure tag as a property
        '<elements><alias name="A" version="1"><include>x</include></alias></elements>',
        # not well-formed
        '<elements><alias name="A" version="1"><proxy>P</alias></elements>',
    ],
    ids=["stray text", "plain", "nested configuration", "structure tag", "broken"],
)
def test_files_only_the_whole_tree_answers_for_give_the_same_findings(tmp_path, monkeypatch, body):
    text = HEAD + body + "</configuration>\n"
    path = tmp_path / "odd.jconf"
    path.write_text(text)
    doctype = tmp_path / "doctype.jconf"
    doctype.write_text(text.replace("<configuration", "<!DOCTYPE x>\n<configuration", 1))
    options = ValidateOptions(environ={})
    found = [d.to_dict() for p in (path, doctype) for d in validate_paths([p], options).diagnostics]
    plain = body == '<elements><alias name="A" version="1"><proxy>P</proxy></alias></elements>'
    for odd in (doctype,) if plain else (path, doctype):  # read whole, not streamed
        assert (
            parse_configuration(odd.read_bytes(), str(odd), FileKind.CONFIGURATION).streamed is None
        )
    monkeypatch.setattr(configload, "parse_configuration", _whole)
    import gadgetctl.validate as validate_module

    monkeypatch.setattr(validate_module, "load_file", _whole_load(validate_module.load_file))
    again = [d.to_dict() for p in (path, doctype) for d in validate_paths([p], options).diagnostics]
    assert found == again


def _whole(data: bytes, path: str, kind: FileKind = FileKind.UNKNOWN):
    return parse_bytes(data, path, kind)


def _whole_load(load_file):
    def load(path, **kwargs):
        kwargs.pop("parse", None)
        return load_file(path, **kwargs)

    return load


def test_large_streamed_file_gives_the_findings_of_the_whole_tree(tmp_path, monkeypatch):
    monkeypatch.setattr(configload, "STREAM_CHUNK", 4096)
    body = "".join(
        f'<alias name="A{i}" version="1"><proxy>{"Nowhere" if i == 0 else f"A{i - 1}"}</proxy>'
        "</alias>\n"
        for i in range(3000)
    )
    path = tmp_path / "chain.jconf"
    path.write_text(HEAD + "<elements>\n" + body + "</elements>\n</configuration>\n")
    options = ValidateOptions(environ={})
    found = [d.to_dict() for d in validate_paths([path], options).diagnostics]
    import gadgetctl.validate as validate_module

    monkeypatch.setattr(validate_module, "load_file", _whole_load(validate_module.load_file))
    assert [d.to_dict() for d in validate_paths([path], options).diagnostics] == found
    assert [d["code"] for d in found] == ["CFG031", "CFG032", "CFG041"]


def test_parse_errors_are_those_of_the_whole_parse():
    data = (HEAD + '<elements><alias name="A"><proxy>P</alias></elements></configuration>').encode()
    streamed, whole = both_ways(data)
    assert streamed.root is None and [d.message for d in streamed.diagnostics] == [
        d.message for d in whole.diagnostics
    ]
    assert etree  # (lxml parses both)
