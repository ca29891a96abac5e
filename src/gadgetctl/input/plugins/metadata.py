"""Reading a plug-in's metadata from its source with ``ast``, without importing it.

The metadata are literal top-level assignments::

    GADGETCTL_API_VERSION = 1
    PLUGIN_NAME = "LinuxJoydev_drv"
    ELEMENT_TYPES = {"linux_joydev": ("digital", "analog")}
    TRANSPORTS = {"linux_joydev": {"kind": "file", "path": "port_name"}}

and a top-level ``def register(registry)``. ``TRANSPORTS`` says which properties of each
element type name its port (kinds and keys in :data:`TRANSPORT_KEYS`); a type with several
transports gives a list of such dicts.
"""

from __future__ import annotations

import ast
import os
from dataclasses import dataclass, field
from pathlib import Path

from gadgetctl.input.kinds import DeviceKind, parse_kinds

API_VERSION = "GADGETCTL_API_VERSION"
PLUGIN_NAME = "PLUGIN_NAME"
ELEMENT_TYPES = "ELEMENT_TYPES"
TRANSPORTS = "TRANSPORTS"
#: Python modules a plug-in needs that gadgetctl does not install by default, each with what
#: to install: ``REQUIRES = {"sdl2": "pip install 'gadgetctl[sdl]'"}``.
REQUIRES = "REQUIRES"
REGISTER = "register"
_NAMES = (API_VERSION, PLUGIN_NAME, ELEMENT_TYPES, TRANSPORTS, REQUIRES)

#: Transport kind -> (required keys, optional keys); values are property names.
TRANSPORT_KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "file": (("path",), ()),
    "serial": (("port",), ("baud",)),
    # group: a literal multicast address; port_unset: the literal port used when the element
    # does not set the port property (a driver default that differs from the definition's)
    "udp": (("port",), ("host", "peer_port", "group", "port_unset")),
    # only sends to host (a property; "host:port" or a fixed port); or to the board whose "mac"
    # answers discovery, when the "method" property says find_mac
    "udp-peer": (("host",), ("mac", "method")),
    "tcp": (("host", "port"), ()),
    "vrpn": (("name",), ("count",)),  # a Device@host name; count: 0 means unused
    "shm": (("key",), ()),  # a System V shared-memory key (trackd)
    "sdl": (("index",), ()),  # an index into the joysticks SDL sees
}


@dataclass
class PluginMetadata:
    """What a driver plug-in declares about itself, read without importing it."""

    api_version: int | None = None
    plugin_name: str | None = None
    element_types: dict[str, tuple[DeviceKind, ...]] = field(default_factory=dict)
    transports: dict[str, list[dict[str, str]]] = field(default_factory=dict)
    requires: dict[str, str] = field(default_factory=dict)  # module -> what to install
    has_register: bool = False
    summary: str = ""
    problems: list[str] = field(default_factory=list)
    api_version_dynamic: bool = False  # assigned, but not as a literal

    def to_dict(self) -> dict[str, object]:
        return {
            "api_version": self.api_version,
            "plugin_name": self.plugin_name,
            "element_types": {
                t: [k.value for k in kinds] for t, kinds in self.element_types.items()
            },
            "transports": {t: [dict(d) for d in specs] for t, specs in self.transports.items()},
            "requires": dict(self.requires),
            "has_register": self.has_register,
            "summary": self.summary,
            "problems": list(self.problems),
        }


def _assignments(tree: ast.Module) -> dict[str, ast.expr]:
    found: dict[str, ast.expr] = {}
    for node in tree.body:
        if isinstance(node, ast.Assign):
            for target in node.targets:
                if isinstance(target, ast.Name) and target.id in _NAMES:
                    found[target.id] = node.value
        elif (
            isinstance(node, ast.AnnAssign)
            and isinstance(node.target, ast.Name)
            and node.value is not None
            and node.target.id in _NAMES
        ):
            found[node.target.id] = node.value
    return found


def _defines_register(tree: ast.Module) -> bool:
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name == REGISTER:
            return True
        if isinstance(node, ast.Assign) and any(
            isinstance(t, ast.Name) and t.id == REGISTER for t in node.targets
        ):
            return True
        if isinstance(node, ast.ImportFrom) and any(
            (a.asname or a.name) == REGISTER for a in node.names
        ):
            return True
    return False


def parse_metadata(source: str, filename: str = "<plugin>") -> PluginMetadata:
    meta = PluginMetadata()
    try:
        tree = ast.parse(source, filename=filename)
    except SyntaxError as err:
        meta.problems.append(f"syntax error at line {err.lineno}: {err.msg}")
        return meta
    doc = ast.get_docstring(tree)
    meta.summary = doc.strip().splitlines()[0] if doc else ""
    meta.has_register = _defines_register(tree)
    values = _assignments(tree)
    for name, node in values.items():
        try:
            value = ast.literal_eval(node)
        except (ValueError, TypeError, SyntaxError, MemoryError, RecursionError):
            if name == API_VERSION:
                meta.api_version_dynamic = True
            meta.problems.append(
                f"{name} is not a literal, so it cannot be read without importing the plug-in"
            )
            continue
        if name == API_VERSION:
            if isinstance(value, int) and not isinstance(value, bool):
                meta.api_version = value
            else:
                meta.problems.append(f"{API_VERSION} must be an integer, not {value!r}")
        elif name == PLUGIN_NAME:
            if isinstance(value, str):
                meta.plugin_name = value
            else:
                meta.problems.append(f"{PLUGIN_NAME} must be a string, not {value!r}")
        elif name == ELEMENT_TYPES:
            _read_element_types(value, meta)
        elif name == TRANSPORTS:
            _read_transports(value, meta)
        elif name == REQUIRES:
            if isinstance(value, dict) and all(
                isinstance(k, str) and isinstance(v, str) for k, v in value.items()
            ):
                meta.requires = dict(value)
            else:
                meta.problems.append(f"{REQUIRES} must be a dict of module name -> what to install")
    if API_VERSION not in values:
        meta.problems.append(f"no {API_VERSION} assignment")
    if not meta.has_register:
        meta.problems.append(f"no {REGISTER}(registry) function")
    return meta


def _read_element_types(value: object, meta: PluginMetadata) -> None:
    if not isinstance(value, dict):
        meta.problems.append(f"{ELEMENT_TYPES} must be a dict of element type -> device types")
        return
    for element_type, kinds in value.items():
        if not isinstance(element_type, str):
            meta.problems.append(f"{ELEMENT_TYPES} key {element_type!r} is not a string")
            continue
        try:
            meta.element_types[element_type] = parse_kinds(kinds)
        except ValueError as err:
            meta.problems.append(f"{ELEMENT_TYPES}[{element_type!r}]: {err}")


def _transport_problem(spec: object) -> str | None:
    if not isinstance(spec, dict) or spec.get("kind") not in TRANSPORT_KEYS:
        return f"must be a dict with a kind of {', '.join(TRANSPORT_KEYS)}"
    required, optional = TRANSPORT_KEYS[spec["kind"]]
    missing = [k for k in required if k not in spec]
    unknown = [k for k in spec if k != "kind" and k not in required + optional]
    if missing or unknown:
        return f"{spec['kind']} transport: " + "; ".join(
            ([f"missing {', '.join(missing)}"] if missing else [])
            + ([f"unknown {', '.join(unknown)}"] if unknown else [])
        )
    if not all(isinstance(v, str) and v for v in spec.values()):
        return "values must be property names"
    return None


def _read_transports(value: object, meta: PluginMetadata) -> None:
    if not isinstance(value, dict):
        meta.problems.append(f"{TRANSPORTS} must be a dict of element type -> transport")
        return
    for element_type, specs in value.items():
        specs = specs if isinstance(specs, (list, tuple)) else [specs]
        good = []
        for spec in specs:
            problem = _transport_problem(spec)
            if problem is None:
                good.append(dict(spec))
            else:
                meta.problems.append(f"{TRANSPORTS}[{element_type!r}]: {problem}")
        if good and isinstance(element_type, str):
            meta.transports[element_type] = good


#: Metadata by source file, with the file's signature (size, mtime_ns, ctime_ns, inode)
#: when read: every validate run asks about the same plug-ins, and a file is parsed again
#: only once it changed (a chmod changes ctime, so an unreadable file is seen too).
_READ_METADATA: dict[str, tuple[tuple[int, int, int, int], PluginMetadata]] = {}
_READ_METADATA_KEPT = 1024


def read_metadata(path: Path) -> PluginMetadata:
    """Metadata of the plug-in whose source file is ``path`` (``__init__.py`` of a package).

    Reads of an unchanged file share one :class:`PluginMetadata`: do not modify it."""
    key = str(path)
    try:
        status = os.stat(key)
        signature = (status.st_size, status.st_mtime_ns, status.st_ctime_ns, status.st_ino)
    except OSError:
        signature = None  # read_text below says why
    known = _READ_METADATA.get(key)
    if signature is not None and known is not None and known[0] == signature:
        return known[1]
    try:
        source = path.read_text(encoding="utf-8")
    except OSError as err:
        return _unreadable(path, err)  # not kept: a permission may be fixed
    except UnicodeDecodeError as err:
        meta = _unreadable(path, err)
    else:
        meta = parse_metadata(source, key)
    if signature is not None:
        if len(_READ_METADATA) >= _READ_METADATA_KEPT:
            _READ_METADATA.pop(next(iter(_READ_METADATA)))
        _READ_METADATA[key] = (signature, meta)
    return meta


def _unreadable(path: Path, err: OSError | UnicodeDecodeError) -> PluginMetadata:
    meta = PluginMetadata()
    meta.problems.append(f"cannot read {path.name}: {getattr(err, 'strerror', None) or err}")
    return meta


def missing_requirements(meta: PluginMetadata) -> list[str]:
    """What a plug-in needs and this Python lacks, one line each (``needs the Python module
    sdl2: pip install 'gadgetctl[sdl]'``), found without importing anything."""
    import importlib.util

    missing = []
    for module, install in meta.requires.items():
        try:
            found = importlib.util.find_spec(module) is not None
        except (ImportError, ValueError):
            found = False
        if not found:
            missing.append(f"needs the Python module {module}: {install}")
    return missing
