"""From a :class:`DriverSpec` to files: the flags and values the templates are rendered
with, the file list, and writing it.

Generated Python is formatted as ``ruff format`` leaves it, at a line length of 88 (ruff's
default) and 100 (gadgetctl's): a construct is written on one line when that fits in 88
columns, and otherwise exploded one item per line with a trailing comma, which both keep.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import tempfile
import textwrap
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from gadgetctl.safewrite import current_umask
from gadgetctl.scaffold.model import DEVICE_TYPES, DriverSpec, ScaffoldError
from gadgetctl.scaffold.render import render

LIMIT = 88
INDENT = "    "

#: Short nouns for the units of each type, for docstrings.
_UNIT_NOUNS = {
    "analog": "axes",
    "digital": "buttons",
    "position": "tracked sensors",
    "glove": "gloves",
    "gesture": "gestures",
    "command": "commands",
    "string": "texts",
    "hat": "hat switches",
}
#: What each base device class reads in its config().
_BASE_READS = {
    "analog": "min and max (Analog)",
    "position": "position_filters (Position)",
    "glove": "glove_position (Glove)",
}
#: A record of each kind for the README's example line.
_EXAMPLE_VALUES = {
    "analog": "0.5 -0.25",
    "digital": "1 0 0 0",
    "position": "0.5 1.5 0.0 90.0 0.0 0.0 ...",
    "glove": "0.75 0.75 0.375 0.0 ...",
    "gesture": "2",
    "command": "7",
    "string": "hello world",
    "hat": "1",
}
_TRANSPORT_SHORT = {
    "serial": "a serial line",
    "udp": "UDP",
    "tcp": "TCP",
    "file": "a FIFO",
    "none": "nothing",
}
_EMULATOR_DESCRIPTION = {
    "serial": "It owns the master side of an ``os.openpty()`` pair; a driver opens the\n"
    "slave (``address``) as a serial port.",
    "udp": "It sends UDP datagrams to a port of this computer (``address``), where the\n"
    "driver receives them.",
    "tcp": "It is a TCP server on this computer (``address``) to which a driver connects,\n"
    "one at a time.",
    "file": "It creates a FIFO (``address``) and writes to whoever opens it for reading, as\n"
    "a device does through its device file.",
}


@dataclass(frozen=True)
class GeneratedFile:
    path: Path  # relative to the spec's target directory
    text: str


@dataclass
class ScaffoldResult:
    spec: DriverSpec
    files: list[GeneratedFile]
    written: bool  # False for a dry run

    @property
    def paths(self) -> list[Path]:
        return [self.spec.target / f.path for f in self.files]

    def to_dict(self) -> dict[str, object]:
        spec = self.spec
        return {
            "name": spec.names.camel,
            "plugin": spec.names.plugin,
            "element_type": spec.names.element_type,
            "types": list(spec.types),
            "transport": spec.transport,
            "vendor": spec.vendor,
            "package": spec.package,
            "distribution": spec.names.distribution if spec.package else None,
            "directory": str(spec.target),
            "plugin_directory": str(spec.plugin_dir),
            "written": self.written,
            "files": [str(p) for p in self.paths],
        }


def escape(text: str) -> str:
    """``text`` for XML character data."""
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def quoteattr(text: str) -> str:
    """``text`` as a double-quoted XML attribute value."""
    return '"' + escape(text).replace('"', "&quot;") + '"'


# -- Python layout helpers -------------------------------------------------------------------


def py_str(text: str) -> str:
    """A double-quoted string literal (ruff format's quote style)."""
    body = text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
    return f'"{body}"'


def py_bytes(data: bytes) -> str:
    """A double-quoted bytes literal."""
    out = []
    for byte in data:
        char = chr(byte)
        if char == "\n":
            out.append("\\n")
        elif char in '"\\':
            out.append("\\" + char)
        elif 0x20 <= byte < 0x7F:
            out.append(char)
        else:
            out.append(f"\\x{byte:02x}")
    return 'b"' + "".join(out) + '"'


def py_inline(value: object) -> str:
    if isinstance(value, str):
        return py_str(value)
    if isinstance(value, bytes):
        return py_bytes(value)
    if isinstance(value, dict):
        return "{" + ", ".join(f"{py_inline(k)}: {py_inline(v)}" for k, v in value.items()) + "}"
    if isinstance(value, tuple):
        inner = ", ".join(py_inline(v) for v in value)
        return f"({inner},)" if len(value) == 1 else f"({inner})"
    return repr(value)


def py_literal(prefix: str, value: object, indent: str = "", suffix: str = "") -> list[str]:
    """``prefix`` + the literal ``value`` + ``suffix`` as lines: one line when it fits,
    else exploded one item per line with trailing commas (recursively)."""
    line = indent + prefix + py_inline(value) + suffix
    if len(line) <= LIMIT or not isinstance(value, (dict, tuple)) or not value:
        return [line]
    if isinstance(value, dict):
        opening, closing = "{", "}"
        items = [(py_inline(k) + ": ", v) for k, v in value.items()]
    else:
        opening, closing = "(", ")"
        items = [("", v) for v in value]
    lines = [indent + prefix + opening]
    for item_prefix, item in items:
        lines += py_literal(item_prefix, item, indent + INDENT, ",")
    lines.append(indent + closing + suffix)
    return lines


def _member_key(name: str) -> tuple[int, str]:
    """isort's order-by-type: constants, then classes, then everything else."""
    if len(name) > 1 and name.isupper():
        return 0, name.lower()
    if name[:1].isupper():
        return 1, name.lower()
    return 2, name.lower()


def py_import(module: str, names: Iterable[str]) -> str:
    """``from module import names`` as ruff's isort writes it."""
    members = sorted(set(names), key=_member_key)
    line = f"from {module} import {', '.join(members)}"
    if len(line) <= LIMIT:
        return line
    return "\n".join([f"from {module} import (", *(f"{INDENT}{m}," for m in members), ")"])


def py_class_header(name: str, bases: list[str]) -> str:
    line = f"class {name}({', '.join(bases)}):"
    if len(line) <= LIMIT:
        return line
    return "\n".join([f"class {name}(", *(f"{INDENT}{b}," for b in bases), "):"])


def py_def_header(name: str, params: list[str], returns: str) -> str:
    line = f"def {name}({', '.join(params)}) -> {returns}:"
    if len(line) <= LIMIT:
        return line
    return "\n".join([f"def {name}(", *(f"{INDENT}{p}," for p in params), f") -> {returns}:"])


def wrap(text: str, indent: str = "", first: str = "", last: str = "") -> str:
    """``text`` filled to LIMIT columns, ``first`` before it and ``last`` after it."""
    lines = textwrap.wrap(first + text + last, width=LIMIT - len(indent), break_on_hyphens=False)
    return "\n".join(indent + line for line in lines)


def join_words(words: list[str]) -> str:
    if len(words) <= 1:
        return "".join(words)
    return ", ".join(words[:-1]) + " and " + words[-1]


# -- flags and values --------------------------------------------------------------------------


def template_flags(spec: DriverSpec) -> dict[str, bool]:
    flags = {name: name in spec.types for name in DEVICE_TYPES}
    flags.update(
        {name: spec.transport == name for name in ("serial", "udp", "tcp", "file", "none")}
    )
    flags["package"] = spec.package
    return flags


def _garbage_lines(spec: DriverSpec) -> list[bytes]:
    lines = [b"no_such_kind 1 2 3\n", b"\xfe\xff not text\n"]
    numeric = [t for t in spec.device_types if t.width > 0]
    if numeric:
        first = numeric[0]
        count = first.units * first.width
        lines.append((first.name + " 1" * (count + 1) + "\n").encode())  # one number too many
        lines.append((first.name + " x" + " 0" * (count - 1) + "\n").encode())  # not a number
    if "string" in spec.types:
        lines.append(b"string \xff\xfe\n")  # not UTF-8
    return lines


def _xml_property(prop) -> list[str]:
    lines = [
        f"    <property valuetype={quoteattr(prop.valuetype)} "
        f"variable={quoteattr('true' if prop.variable else 'false')} name={quoteattr(prop.name)}>",
        f"      <help>{escape(prop.help)}</help>",
    ]
    default = "" if prop.default is None else f" defaultvalue={quoteattr(prop.default)}"
    lines.append(f"      <value label={quoteattr(prop.label)}{default}/>")
    lines += [f"      <allowed_type>{t}</allowed_type>" for t in prop.allowed_types]
    lines.append("    </property>")
    return lines


def _jconf_values(spec: DriverSpec) -> list[str]:
    lines = []
    for prop in spec.properties():
        values = prop.examples or (() if prop.example is None else (prop.example,))
        lines += [f"         <{prop.name}>{escape(v)}</{prop.name}>" for v in values]
    return lines


def _jconf_proxies(spec: DriverSpec) -> list[str]:
    lines = []
    aliases = spec.aliases()
    for _alias, proxy, proxy_type, unit in aliases:
        lines += [
            f'      <{proxy_type} name={quoteattr(proxy)} version="1">',
            f"         <device>{spec.names.camel}</device>",
            f"         <unit>{unit}</unit>",
            f"      </{proxy_type}>",
        ]
    if "gesture" in spec.types:
        lines.append(
            "      <!-- No gesture proxy: the standard gesture_proxy only accepts "
            "simulated_glove_gesture devices (and VR Juggler never activates one); "
            "gadgetctl monitor shows the device's gestures. -->"
        )
    if aliases:
        lines.append("      <!-- Applications look their inputs up by these names. -->")
    for alias, proxy, _proxy_type, _unit in aliases:
        lines += [
            f'      <alias name={quoteattr(alias)} version="1">',
            f"         <proxy>{escape(proxy)}</proxy>",
            "      </alias>",
        ]
    return lines


def _dispatch(spec: DriverSpec) -> list[str]:
    lines = []
    for index, device_type in enumerate(spec.device_types):
        keyword = "if" if index == 0 else "elif"
        lines.append(f"{INDENT * 2}{keyword} record.kind == {py_str(device_type.name)}:")
        if device_type.name == "position":
            call = "self.add_position_sample([pose_matrix(*pose) for pose in record.values])"
        else:
            call = f"self.add_{device_type.name}_sample(record.values)"
        lines.append(INDENT * 3 + call)
    return lines


def _category(spec: DriverSpec) -> str:
    for preferred in ("position", "glove"):
        if preferred in spec.types:
            return DEVICE_TYPES[preferred].category or "/Devices"
    if len(spec.types) == 1:
        return DEVICE_TYPES[spec.types[0]].category or "/Devices"
    return "/Devices"


def template_values(spec: DriverSpec) -> dict[str, str]:
    names = spec.names
    camel, element_type = names.camel, names.element_type
    driver_class, record_class = camel, camel + "Record"
    device_class, emulator_class = camel + "Device", camel + "Emulator"
    types = spec.device_types
    kinds_phrase = join_words(spec.types)
    units_summary = join_words(
        [
            f"{t.units} {t.name} units ({_UNIT_NOUNS[t.name]})"
            if t.units > 1
            else f"1 {t.name} unit"
            for t in types
        ]
    )
    base_reads = ", ".join(
        ["the element's name"] + [_BASE_READS[t] for t in spec.types if t in _BASE_READS]
    )
    parents = [t.parent for t in types if t.parent] or ["input_device"]
    transport = spec.transport
    emulated = transport != "none"

    kinds_table = [
        f'{INDENT}"{t.name}": ({t.units}, {t.width}, {t.number}),  # {t.layout}' for t in types
    ]
    units_table = [f'{INDENT}"{t.name}": {t.units},' for t in types]
    garbage_table = [f"{INDENT}{py_bytes(line)}," for line in _garbage_lines(spec)]

    metadata = spec.transport_metadata()
    transports_assignment = (
        "\n".join(py_literal("TRANSPORTS = ", {element_type: metadata})) if metadata else ""
    )
    element_types_assignment = "\n".join(
        py_literal("ELEMENT_TYPES = ", {element_type: tuple(spec.types)})
    )

    gadgetctl_names = [t.device_class for t in types] + ["DeviceConfigError", "SamplingMode"]
    plugin = names.plugin
    if emulated:
        plugin_imports = [
            py_import(
                f"{plugin}.emulator", ["GARBAGE", emulator_class, "encode_record", "pattern"]
            ),
            py_import(
                f"{plugin}.standalone",
                ["KINDS", driver_class, record_class, "decode_record", "split_records"],
            ),
        ]
    else:
        plugin_imports = [
            py_import(f"{plugin}.standalone", ["KINDS", driver_class, record_class, "read_device"])
        ]
    if "position" in spec.types:
        plugin_imports.append(py_import(f"{plugin}.wrapper", ["pose_matrix"]))

    aliases = tuple(alias for alias, *_ in spec.aliases())
    config_values = {
        "serial": "port=emulator.address",
        "file": "path=emulator.address",
        "udp": "port=str(emulator.port)",
        "tcp": "host=emulator.host, port=str(emulator.port)",
        "none": "",
    }[transport]
    first = types[0]
    tested = (
        f"the standalone driver against its emulator over {_TRANSPORT_SHORT[transport]}"
        if emulated
        else "the standalone driver"
    )
    address = spec.example_address
    example_where = {
        "serial": f"the pty link {address}",
        "file": f"the FIFO {address}",
        "udp": f"UDP port {address} on 127.0.0.1",
        "tcp": f"TCP port {address} on 127.0.0.1",
        "none": "",
    }[transport]
    summary = (
        f"Provides {units_summary} over {spec.transport_info.phrase}."
        if emulated
        else f"Provides {units_summary}; {spec.transport_info.phrase}."
    )
    definition_help = (
        f"{spec.label}: {units_summary}, over {spec.transport_info.phrase}. "
        f"(Generated by gadgetctl scaffold: describe the device here.)"
    )
    if not emulated:
        definition_help = (
            f"{spec.label}: {units_summary}, read by the driver itself. "
            f"(Generated by gadgetctl scaffold: describe the device here.)"
        )
    device_comment = (
        f"The device. Its transport properties match the emulator's defaults "
        f"(gadgetctl emulate {plugin})."
        if emulated
        else "The device: the driver reads it rate times per second."
    )
    return {
        "label": spec.label,
        "label_xml": escape(spec.label),
        "camel": camel,
        "plugin": plugin,
        "element_type": element_type,
        "distribution": names.distribution,
        "driver_class": driver_class,
        "record_class": record_class,
        "device_class": device_class,
        "emulator_class": emulator_class,
        "error_class": camel + "Error",
        "disconnected_class": camel + "Disconnected",
        "summary": wrap(summary),
        "standalone_intro": wrap(
            f"The device needs no port: the driver reads it directly (for example through the "
            f"vendor's library) in :func:`read_device`, whose placeholder makes up {kinds_phrase} data."
            if not emulated
            else f"The device sends its data over {spec.transport_info.phrase}. The placeholder protocol "
            f"is one line of ASCII text per record, ``<kind> <numbers...>``: {kinds_phrase}, with "
            f"the units of each kind in turn (see ``KINDS``). Everything about the data format is "
            f"in the PROTOCOL section below: replace it with the real device's protocol, and the "
            f"emulator's copy in emulator.py with it."
        ),
        "class_summary": wrap(f"An ``{element_type}`` element: {units_summary}.", INDENT, '"""'),
        "config_doc": wrap(
            f"Read the element. The base types' configuration comes first (the "
            f'driver guide\'s "important" note): {base_reads}.',
            INDENT * 2,
            '"""',
            '"""',
        ),
        "tests_intro": wrap(
            f"First {tested}, then the whole plug-in in gadgetctl's input manager "
            "with example.jconf."
        ),
        "kinds_phrase": kinds_phrase,
        "units_summary": units_summary,
        "base_reads": base_reads,
        "transport_phrase": spec.transport_info.phrase,
        "transport_short": _TRANSPORT_SHORT[transport],
        "emulator_description": _EMULATOR_DESCRIPTION.get(transport, ""),
        "extra_libraries": ", pyserial" if transport == "serial" else "",
        "element_types_assignment": element_types_assignment,
        "transports_assignment": transports_assignment,
        "kinds_table": "\n".join(kinds_table),
        "units_table": "\n".join(units_table),
        "garbage_table": "\n".join(garbage_table),
        "example_address": address,
        "gadgetctl_import": py_import("gadgetctl.input", gadgetctl_names),
        "standalone_import": py_import(".standalone", [driver_class, record_class]),
        "class_header": py_class_header(device_class, [t.device_class for t in types]),
        "disconnected_header": py_class_header(camel + "Disconnected", [camel + "Error"]),
        "read_records_header": py_def_header(
            "read_records", [f"driver: {driver_class}"], f"list[{record_class}]"
        ),
        "connect_header": py_def_header("connect", [f"emulator: {emulator_class}"], driver_class),
        "dispatch": "\n".join(_dispatch(spec)),
        "plugin_imports": "\n".join(plugin_imports),
        "aliases_assignment": "\n".join(py_literal("ALIASES = ", aliases))
        if aliases
        else "ALIASES = ()",
        "config_values": config_values,
        "tests_where": "the project's folder" if spec.package else "the plug-in's folder",
        "tests_against": " against its emulator (over the real transport)" if emulated else "",
        "definition_help": escape(definition_help),
        "parents": "\n".join(f"    <parent>{p}</parent>" for p in dict.fromkeys(parents)),
        "category": _category(spec),
        "properties": "\n".join(line for prop in spec.properties() for line in _xml_property(prop)),
        "device_comment": device_comment,
        "device_properties": "\n".join(_jconf_values(spec)),
        "proxies_and_aliases": "\n".join(_jconf_proxies(spec)),
        "kinds_rows": "\n".join(f"| `{t.name}` | {t.units} | {t.layout} |" for t in types),
        "example_line": f"{first.name} {_EXAMPLE_VALUES[first.name]}",
        "example_where": example_where,
        "run_commands": "\n".join(
            aligned(
                run_steps(
                    spec,
                    f"src/{plugin}" if spec.package else plugin,
                    ".",
                )
            )
        ),
        "transport_properties": join_words([f"`{p.name}`" for p in spec.transport_properties()]),
        "position_note": (
            ", and position records into 4x4 matrices (`pose_matrix()`)"
            if "position" in spec.types
            else ""
        ),
        "sampling_note": (
            " from a thread shared with other devices, `rate` times per second"
            if not emulated
            else " in a loop in the device's own thread; `sample()` returns after at "
            "most `SAMPLE_TIMEOUT` seconds, so the device can stop"
        ),
    }


# -- files ---------------------------------------------------------------------------------------


def _plan(spec: DriverSpec) -> list[tuple[str, str]]:
    """(template, path relative to the target) for every file."""
    plugin = f"src/{spec.names.plugin}/" if spec.package else ""
    files = [
        ("__init__.py.tmpl", f"{plugin}__init__.py"),
        ("standalone.py.tmpl", f"{plugin}standalone.py"),
        ("wrapper.py.tmpl", f"{plugin}wrapper.py"),
    ]
    if spec.transport != "none":
        files.append(("emulator.py.tmpl", f"{plugin}emulator.py"))
    files += [
        ("definition.jdef.tmpl", f"{plugin}{spec.names.element_type}.jdef"),
        ("example.jconf.tmpl", f"{plugin}example.jconf"),
        ("tests/conftest.py.tmpl", f"{plugin}tests/conftest.py"),
        ("tests/test_driver.py.tmpl", f"{plugin}tests/test_{spec.names.element_type}.py"),
        ("README.md.tmpl", "README.md"),
    ]
    if spec.package:
        files.append(("pyproject.toml.tmpl", "pyproject.toml"))
    return files


def generate(spec: DriverSpec) -> list[GeneratedFile]:
    """Every file of the driver ``spec`` describes, rendered (nothing is written)."""
    flags, values = template_flags(spec), template_values(spec)
    return [
        GeneratedFile(Path(path), _tidy(render(template, flags, values)))
        for template, path in _plan(spec)
    ]


def _tidy(text: str) -> str:
    """No trailing blanks, at most two blank lines in a row, exactly one final newline."""
    text = "\n".join(line.rstrip() for line in text.splitlines())
    return re.sub(r"\n{4,}", "\n\n\n", text).strip("\n") + "\n"


def scaffold(spec: DriverSpec, *, force: bool = False, dry_run: bool = False) -> ScaffoldResult:
    """Generate the driver and write it under ``spec.target``, which must not exist unless
    ``force`` (then the generated files are overwritten and other files left alone).
    Raises :class:`ScaffoldError`. A dry run checks the same and writes nothing."""
    target = spec.target
    if target.exists() and not force:
        what = "directory" if target.is_dir() else "file"
        raise ScaffoldError(
            f"{target} already exists ({what}); choose another --dir or NAME, "
            "or give --force to overwrite the generated files in it"
        )
    if target.exists() and not target.is_dir():
        raise ScaffoldError(f"{target} exists and is not a directory")
    if spec.directory.exists() and not spec.directory.is_dir():
        raise ScaffoldError(f"--dir {spec.directory} is not a directory")
    files = generate(spec)
    if dry_run:
        return ScaffoldResult(spec, files, written=False)
    _write_tree(target, files, force=force)
    return ScaffoldResult(spec, files, written=True)


def _write_tree(target: Path, files: list[GeneratedFile], *, force: bool) -> None:
    """Write ``files`` into a temporary directory beside ``target`` and move it into place
    whole (with ``force`` into an existing ``target``, file by file once all are complete),
    so a failure (full disk, permissions) leaves neither half a plug-in nor a stray
    temporary file, and a second run starts afresh."""
    created = _missing_ancestors(target.parent)
    staging = None
    moving = False
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(
            tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
        )
        for generated in files:
            path = staging / generated.path
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(generated.text, encoding="utf-8")
        mode = 0o777 & ~current_umask()
        for directory in [staging, *(p for p in staging.rglob("*") if p.is_dir())]:
            directory.chmod(mode)
        if not force or not target.exists():
            os.rename(staging, target)
            staging = None
            return
        moving = True
        for generated in files:
            (target / generated.path).parent.mkdir(parents=True, exist_ok=True)
            os.replace(staging / generated.path, target / generated.path)
    except OSError as err:
        if not target.exists():
            for directory in reversed(created):
                with contextlib.suppress(OSError):
                    directory.rmdir()
        done = "" if moving else "; nothing written"
        raise ScaffoldError(f"cannot write {target}: {err.strerror or err}{done}") from None
    finally:
        if staging is not None:
            shutil.rmtree(staging, ignore_errors=True)


def _missing_ancestors(directory: Path) -> list[Path]:
    """``directory`` and its parents that do not exist yet, outermost first."""
    missing = []
    while not directory.exists() and directory != directory.parent:
        missing.append(directory)
        directory = directory.parent
    return missing[::-1]


def run_steps(spec: DriverSpec, plugin_dir: str, where: str) -> list[tuple[str, str]]:
    """(command, what it does) to try a generated driver: ``plugin_dir`` is the plug-in
    folder and ``where`` the folder holding it (or the project, with --package), both as
    the reader will type them."""
    plugin = spec.names.plugin
    emulated = spec.transport != "none"
    if spec.package:
        steps = [
            (f"gadgetctl validate {plugin_dir}", "the .jdef and example.jconf: clean"),
            (
                f"pip install --editable '{where}[test]'",
                "gadgetctl finds it by its entry point; [test] brings pytest",
            ),
            ("gadgetctl drivers list", f"shows {plugin}"),
            (f"gadgetctl drivers load {plugin}", "imports and checks it"),
        ]
        if emulated:
            steps.append((f"gadgetctl emulate {plugin}", "the device, in a second terminal"))
        tests = "python -m pytest" if where == "." else f"cd {where} && python -m pytest"
    else:
        steps = [
            (f"gadgetctl validate {plugin_dir}", "the .jdef and example.jconf: clean"),
            (f"gadgetctl drivers list --driver-path {where}", f"shows {plugin}"),
            (f"gadgetctl drivers load --driver-path {where} {plugin}", "imports and checks it"),
        ]
        if emulated:
            steps.append(
                (
                    f"gadgetctl emulate --driver-path {where} {plugin}",
                    "the device, in a second terminal",
                )
            )
        tests = f"cd {plugin_dir} && python -m pytest"
    steps.append((f"gadgetctl monitor {plugin_dir}/example.jconf", "live samples"))
    if not spec.package:  # a package's [test] extra brings pytest
        steps.append(("python -m pip install pytest", "the test runner, unless you have it"))
    steps.append((tests, "the generated tests"))
    return steps


def aligned(steps: list[tuple[str, str]], indent: str = "") -> list[str]:
    width = max(len(command) for command, _ in steps)
    return [f"{indent}{command.ljust(width)}  # {note}" for command, note in steps]


def summary_lines(result: ScaffoldResult, cwd: Path | None = None) -> list[str]:
    """What the command prints: the names, the files and the next steps."""
    spec = result.spec
    names = spec.names

    def shown(path: Path) -> str:
        try:
            return os.path.relpath(path, cwd) if cwd is not None else str(path)
        except ValueError:
            return str(path)

    lines = [
        f"{names.camel}: plug-in {names.plugin}, element type {names.element_type}, "
        f"{join_words(list(spec.types))} over {spec.transport_info.phrase}"
    ]
    verb = "created" if result.written else "would create"
    lines += [f"  {verb} {shown(p)}" for p in result.paths]
    if not result.written:
        return lines
    plugin_dir = shown(spec.plugin_dir)
    where = shown(spec.target) if spec.package else shown(spec.plugin_dir.parent)
    lines.append("next:")
    lines += aligned(run_steps(spec, plugin_dir, where), "  ")
    lines.append(
        f"The protocol goes into the PROTOCOL section of {plugin_dir}/standalone.py "
        f"(see {shown(spec.target / 'README.md')})."
    )
    return lines
