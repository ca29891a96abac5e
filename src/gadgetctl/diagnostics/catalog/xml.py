"""Diagnostic codes of the `xml` category: reading files and their format markers."""

from gadgetctl.diagnostics.codes import Code
from gadgetctl.diagnostics.levels import Category, Severity

C = Category.XML
E, W, I = Severity.ERROR, Severity.WARNING, Severity.INFO

CODES: list[Code] = [
    Code(
        "XML001",
        C,
        E,
        "XML is not well-formed",
        "The file is not well-formed XML, so nothing else in it can be checked. The location "
        "is where the XML parser gave up; the real mistake is often just before it.",
        '<elements>\n  <alias name="A" version="1">\n</elements>   <!-- alias never closed -->',
        "Close or correct the element at the reported position.",
    ),
    Code(
        "XML002",
        C,
        E,
        "bytes not valid in the declared encoding",
        "The file declares an encoding (UTF-8 when it declares none), but contains bytes that are "
        "not valid in it, typically a Latin-1 character such as a registered sign in a UTF-8 "
        "file. Strict XML parsers (VRJConfig, Python, xmllint) refuse such a file; VR Juggler's "
        "C++ loader does not notice. gadgetctl reads the rest of the file as Latin-1 so that "
        "the later checks still run.",
        "<help>Flock of Birds\\xae hardware</help>   (byte 0xAE in a UTF-8 file)",
        "Re-save the file as UTF-8, or declare the encoding it really uses.",
    ),
    Code(
        "XML003",
        C,
        E,
        "document type declaration or entity",
        "JCCL files never need a DOCTYPE. gadgetctl never loads a DTD and never expands "
        "entities, internal or external, so a file that relies on them would be read "
        "differently than its author expects; a file that uses them to reach other files or "
        "the network is hostile.",
        '<!DOCTYPE configuration [<!ENTITY x SYSTEM "file:///etc/passwd">]>',
        "Remove the DOCTYPE and write the text the entity stood for.",
    ),
    Code(
        "XML004",
        C,
        E,
        "file too large",
        "The file is larger than the limit (--max-size, 16 MiB by default). Configuration and "
        "definition files are a few kilobytes; a file this large is not one, or is damaged. "
        "It is not read, which keeps time and memory bounded.",
        "a 100 MB .jconf",
        "Check that the path is right, or raise --max-size.",
    ),
    Code(
        "XML005",
        C,
        E,
        "not a regular file",
        "The path names a device, a FIFO, a socket or a directory, not a file. Reading it could "
        "block for ever (a FIFO without a writer) or never end (/dev/zero), so gadgetctl refuses "
        "it before reading anything.",
        "gadgetctl validate /dev/zero",
        "Give the path of a saved .jconf or .jdef file (copy a stream to a file first).",
    ),
    Code(
        "XML010",
        C,
        W,
        "missing file-format processing instruction",
        "JCCL files start with <?org-vrjuggler-jccl-settings ...?> naming the file-format "
        'version (configuration.version="3.0" in .jconf files, definition.version="3.1" in '
        ".jdef files). VR Juggler's C++ loader ignores it, but VRJConfig refuses a file "
        "without it.",
        '<?xml version="1.0"?>\n<configuration name="x" ...>',
        'Add <?org-vrjuggler-jccl-settings configuration.version="3.0"?> after the XML declaration.',
    ),
    Code(
        "XML011",
        C,
        E,
        "unexpected file-format version",
        "The processing instruction names a file-format version gadgetctl and VRJConfig do not "
        "know (configurations are format 3.0, definitions 3.1), or the wrong kind of version "
        "for the file.",
        '<?org-vrjuggler-jccl-settings configuration.version="3.1"?>',
        'Use configuration.version="3.0" or definition.version="3.1".',
    ),
    Code(
        "XML012",
        C,
        E,
        "wrong or missing namespace",
        "The root element is not in the JCCL namespace of its format. There is no "
        "configuration namespace 3.1; the configuration namespace is "
        "http://www.vrjuggler.org/jccl/xsd/3.0/configuration and the definition namespace "
        "http://www.vrjuggler.org/jccl/xsd/3.1/definition. Editors and schema validation rely "
        "on it; `gadgetctl upgrade` can fix it.",
        '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.1/configuration" name="x">',
        "Run `gadgetctl upgrade FILE` or set the namespace by hand.",
    ),
    Code(
        "XML013",
        C,
        E,
        "older definition file format",
        "The definition file is in format 3.0 (namespace .../xsd/3.0/definition). VR Juggler 3 "
        "loads only format 3.1. The upgrade inserts <abstract>false</abstract> in each "
        "definition_version and moves the file to the 3.1 namespace.",
        '<?org-vrjuggler-jccl-settings definition.version="3.0"?>',
        "Run `gadgetctl upgrade FILE` to convert it to format 3.1.",
    ),
    Code(
        "XML014",
        C,
        E,
        "unknown root element",
        "The file is neither a JCCL configuration (root <configuration>) nor a definition "
        "(root <definition>).",
        '<config name="x"/>',
        "Check that this is a JCCL file, or that the root element is spelled right.",
    ),
    Code(
        "XML015",
        C,
        W,
        "stray text between child elements",
        "An element that holds child elements (<elements>, an element instance, a definition's "
        "<definition_version>) also holds text of its own. JCCL elements hold either a value "
        "or child elements, never both; the schemas let it pass and VR Juggler ignores the "
        "text without a word, so whatever it was meant to say is lost. Generators that write a "
        "count or a stray value into the file are the usual cause.",
        "<surface_viewport ...>\n  <origin>0.0</origin>\n  8\n  <size>1.0</size>",
        "Remove the text, or move it into the property it was meant for.",
    ),
]
