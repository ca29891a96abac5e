"""Words for dynamic shell completion: `gadgetctl __complete KIND [WORD...]`.

The completion scripts in ``completions/`` call this for the words they cannot know in
advance: driver plug-ins, emulators, diagnostic codes, definition names and the element
names of the configurations already on the command line. Each candidate is printed on its
own line, optionally followed by a tab and a short description (fish and zsh show it).

It runs on every Tab press, so it stays light: no typer, rich, lxml or numpy, no
dataclasses, not even pathlib; plug-in folders and ``.jdef`` files are listed, not loaded, and configuration
files are scanned for element names with a bounded read instead of being parsed.
"""

from __future__ import annotations

import os
import re
import sys

TYPE_CHECKING = False  # not `typing`'s: importing typing costs more than this whole module
if TYPE_CHECKING:
    from collections.abc import Iterable, Iterator

KINDS = ("drivers", "emulators", "codes", "definitions", "elements", "inputs", "keyboards")

MAX_CONFIG_BYTES = 2 * 1024 * 1024  # read of one configuration file
MAX_CONFIG_FILES = 32  # configurations and their includes, per completion
MAX_JDEF_HEAD = 4096  # a .jdef's definition name is near its top

_DRIVER_PATH_ENV = "GADGETCTL_DRIVER_PATH"
_ENTRY_POINT_GROUP = "gadgetctl.drivers"
_SKIPPED_MODULES = {"conftest.py", "setup.py"}
_KEYBOARD_TYPE = "keyboard_mouse_device"
# Standard element types that are not devices, proxies or aliases (the bundled definitions
# outside the /Devices and /Proxies categories): `monitor` cannot show them.
NOT_INPUT_TYPES = frozenset(
    {
        "cluster_manager",
        "cluster_node",
        "corba_performance_monitor",
        "corba_remote_reconfig",
        "default_simulator",
        "display_system",
        "display_window",
        "event_emitter",
        "full_position_transform_filter",
        "gadget_logger",
        "input_manager",
        "opengl_frame_buffer_config",
        "position_calibration_filter",
        "position_transform_filter",
        "simulator_viewport",
        "sound",
        "sound_manager_sonix",
        "surface_viewport",
        "user",
    }
)

_TOKEN = re.compile(
    r"<!--.*?-->|<!\[CDATA\[.*?\]\]>|<[?!][^>]*>"
    r"|<(/?)([^\s/>!?]+)((?:[^>\"']|\"[^\"]*\"|'[^']*')*)>",
    re.S,
)
_NAME_ATTR = re.compile(r"""(?:^|\s)name\s*=\s*(?:"([^"]*)"|'([^']*)')""")
_DEFINITION_NAME = re.compile(
    r"""<(?:\w+:)?definition\s(?:[^>"']|"[^"]*"|'[^']*')*?\bname\s*=\s*(?:"([^"]*)"|'([^']*)')"""
)
_ENTITY = re.compile(r"&(#x[0-9a-fA-F]+|#[0-9]+|lt|gt|amp|quot|apos);")
_NAMED = {"lt": "<", "gt": ">", "amp": "&", "quot": '"', "apos": "'"}
_VARIABLE = re.compile(r"\$\(([A-Za-z_]\w*)\)")


# --- the words already on the command line -------------------------------------------------


def _unquote(word: str) -> str:
    """A shell word as the command will see it (quotes and backslashes removed, ~ expanded)."""
    if len(word) >= 2 and word[0] == word[-1] and word[0] in "'\"":
        word = word[1:-1]
    elif word[:1] in "'\"":
        word = word[1:]
    else:
        word = re.sub(r"\\(.)", r"\1", word)
    return os.path.expanduser(word)


def option_values(words: list[str], *names: str) -> list[str]:
    """Values of the options ``names`` (``--opt VALUE`` and ``--opt=VALUE``) among ``words``."""
    found = []
    for i, word in enumerate(words):
        option, equals, value = word.partition("=")
        if option in names:
            if equals:
                found.append(_unquote(value))
            elif i + 2 < len(words) and words[i + 1] == "=":  # bash splits `--opt=VALUE` at the =
                found.append(_unquote(words[i + 2]))
            elif i + 1 < len(words):
                found.append(_unquote(words[i + 1]))
    return found


def _expand(raw: str) -> str:
    """``${VAR}``, ``$VAR``, ``$(VAR)`` and ``~`` expanded (unset variables left as written)."""
    raw = _VARIABLE.sub(lambda m: os.environ.get(m.group(1), m.group(0)), raw)
    return os.path.expanduser(os.path.expandvars(raw.strip()))


def _data_root() -> str:
    package = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
    installed = os.path.join(package, "_data")
    return installed if os.path.isdir(installed) else os.path.dirname(os.path.dirname(package))


# --- driver plug-ins -----------------------------------------------------------------------


def _plugins_in(directory: str) -> Iterator[tuple[str, str, bool]]:
    """(name, path, is_package) of each plug-in directly inside ``directory``."""
    try:
        entries = sorted(os.scandir(directory), key=lambda e: e.name)
    except OSError:
        return
    for entry in entries:
        name = entry.name
        if name.startswith((".", "_")):
            continue
        path = entry.path
        if entry.is_dir() and os.path.isfile(os.path.join(path, "__init__.py")):
            yield name, path, True
        elif (
            name.endswith(".py")
            and name not in _SKIPPED_MODULES
            and not name.startswith("test_")
            and entry.is_file()
        ):
            yield name[:-3], path, False


def _entry_point_plugins() -> Iterator[tuple[str, str, bool]]:
    """Plug-ins installed packages declare (``[gadgetctl.drivers]`` in ``entry_points.txt``),
    read from the distributions' metadata files without importlib.metadata."""
    for base in sys.path:
        try:
            folders = [
                e for e in os.scandir(base or ".") if e.name.endswith((".dist-info", ".egg-info"))
            ]
        except OSError:
            continue
        for folder in folders:
            try:
                with open(
                    os.path.join(folder.path, "entry_points.txt"),
                    encoding="utf-8",
                    errors="replace",
                ) as f:
                    text = f.read(65536)
            except OSError:
                continue
            for name, module in _entry_points(text):
                located = _module_file(module)
                if located is not None:
                    yield name, *located


def _entry_points(text: str) -> Iterator[tuple[str, str]]:
    section = ""
    for line in text.splitlines():
        line = line.strip()
        if line.startswith("[") and line.endswith("]"):
            section = line[1:-1].strip()
        elif section == _ENTRY_POINT_GROUP and "=" in line:
            name, _, value = line.partition("=")
            yield name.strip(), value.partition(":")[0].strip()


def _module_file(module: str) -> tuple[str, bool] | None:
    parts = module.split(".")
    for base in sys.path:
        package = os.path.join(base or ".", *parts)
        if os.path.isfile(os.path.join(package, "__init__.py")):
            return package, True
        if os.path.isfile(package + ".py"):
            return package + ".py", False
    return None


def plugins(words: list[str]) -> dict[str, tuple[str, bool]]:
    """Plug-ins in search order (entry points, bundled, GADGETCTL_DRIVER_PATH, --driver-path);
    the first of a name wins, as in discovery."""
    directories = [os.path.join(_data_root(), "drivers")]
    directories += [
        _expand(raw)
        for raw in os.environ.get(_DRIVER_PATH_ENV, "").split(os.pathsep)
        if raw.strip()
    ]
    directories += [_expand(raw) for raw in option_values(words, "--driver-path")]
    found: dict[str, tuple[str, bool]] = {}
    for name, path, package in _entry_point_plugins():
        found.setdefault(name, (path, package))
    for directory in directories:
        for name, path, package in _plugins_in(directory):
            found.setdefault(name, (path, package))
    return found


def driver_candidates(words: list[str]) -> Iterator[str]:
    for name, (path, package) in plugins(words).items():
        yield f"{name}\t{'package' if package else 'module'} in {os.path.dirname(path)}"


def emulator_candidates(words: list[str]) -> Iterator[str]:
    for name, (path, package) in plugins(words).items():
        if package and os.path.isfile(os.path.join(path, "emulator.py")):
            yield f"{name}\temulator in {path}"


# --- diagnostic codes ----------------------------------------------------------------------


_CODE_ENTRY = re.compile(r'\bCode\(\s*"([A-Z]+[0-9]+)",\s*\w+,\s*\w+,\s*"((?:[^"\\]|\\.)*)"')


def code_candidates(words: list[str]) -> Iterator[str]:
    """Codes and titles, read from the catalog's sources (its entries all start
    ``Code("XML001", C, E, "title"``; a test compares this with the imported catalog), which
    costs a fraction of importing it; the import is the fallback."""
    catalog_dir = os.path.join(
        os.path.dirname(os.path.dirname(os.path.realpath(__file__))), "diagnostics", "catalog"
    )
    found: dict[str, str] = {}
    try:
        for name in sorted(os.listdir(catalog_dir)):
            if name.endswith(".py"):
                with open(os.path.join(catalog_dir, name), encoding="utf-8") as source:
                    found.update(_CODE_ENTRY.findall(source.read()))
    except OSError:
        found = {}
    if not found:
        from gadgetctl.diagnostics.codes import catalog

        found = {code: entry.title for code, entry in catalog().items()}
    for code, title in sorted(found.items()):
        yield f"{code}\t{title}"


# --- definitions ---------------------------------------------------------------------------


def definition_directories(words: list[str]) -> list[str]:
    """The definition search path the command line describes, without configurations'
    ``<definition_path>`` (plus plug-in folders carrying .jdef files)."""
    directories = [] if "--no-bundled" in words else [os.path.join(_data_root(), "definitions")]
    if os.environ.get("VJ_BASE_DIR"):
        directories.append(
            os.path.join(
                _expand(os.environ["VJ_BASE_DIR"]), "share", "vrjuggler", "data", "definitions"
            )
        )
    directories += [
        _expand(raw)
        for raw in os.environ.get("JCCL_DEFINITION_PATH", "").split(os.pathsep)
        if raw.strip()
    ]
    directories += [_expand(raw) for raw in option_values(words, "--definitions", "-d")]
    directories += [path for path, package in plugins(words).values() if package]
    return directories


def _definition_name(path: str) -> str:
    try:
        with open(path, "rb") as stream:
            head = stream.read(MAX_JDEF_HEAD).decode("utf-8", errors="replace")
    except OSError:
        return ""
    match = _DEFINITION_NAME.search(head)
    if match is None:
        return os.path.basename(path)[: -len(".jdef")]
    return _unescape(match.group(1) if match.group(1) is not None else match.group(2))


def definition_candidates(words: list[str]) -> Iterator[str]:
    seen: set[str] = set()
    for directory in definition_directories(words):
        try:
            files = sorted(
                e.path for e in os.scandir(directory) if e.name.endswith(".jdef") and e.is_file()
            )
        except OSError:
            continue
        for file in files:
            name = _definition_name(file)
            if name and name not in seen:
                seen.add(name)
                yield f"{name}\t{file}"


# --- element names of the configurations on the line ---------------------------------------


def _unescape(text: str) -> str:
    def one(match: re.Match[str]) -> str:
        entity = match.group(1)
        if entity.startswith("#"):
            try:
                return chr(int(entity[2:], 16) if entity[1] in "xX" else int(entity[1:]))
            except (ValueError, OverflowError):
                return match.group(0)
        return _NAMED[entity]

    return _ENTITY.sub(one, text)


def scan_configuration(text: str) -> tuple[list[tuple[str, str]], list[str]]:
    """(element type, name) of each element of a ``.jconf`` text, and its includes, found by
    a scan of its tags (no parser, no entities): elements are the children of ``<elements>``
    under the root, includes the root's ``<include>`` children."""
    elements: list[tuple[str, str]] = []
    includes: list[str] = []
    stack: list[str] = []
    include_start = -1
    for match in _TOKEN.finditer(text):
        closing, tag, attributes = match.group(1), match.group(2), match.group(3)
        if tag is None:
            continue
        local = tag.rpartition(":")[2]
        if closing:
            if stack and stack[-1] == local:
                stack.pop()
                if local == "include" and len(stack) == 1 and include_start >= 0:
                    includes.append(_unescape(text[include_start : match.start()]).strip())
                    include_start = -1
            continue
        empty = attributes.rstrip().endswith("/")
        if len(stack) == 2 and stack[1] == "elements":
            named = _NAME_ATTR.search(attributes)
            if named:
                elements.append(
                    (
                        local,
                        _unescape(named.group(1) if named.group(1) is not None else named.group(2)),
                    )
                )
        elif len(stack) == 1 and local == "include" and not empty:
            include_start = match.end()
        if not empty:
            stack.append(local)
    return elements, includes


def _read_bounded(path: str) -> str:
    with open(path, "rb") as stream:
        return stream.read(MAX_CONFIG_BYTES).decode("utf-8", errors="replace")


def configuration_files(words: list[str]) -> list[str]:
    """The configuration files on the line: existing files ending in ``.jconf``."""
    files = []
    for word in words:
        if word.startswith("-"):
            continue
        path = _unquote(word)
        if path.endswith(".jconf") and os.path.isfile(path):
            files.append(path)
    return files


def configuration_elements(paths: Iterable[str]) -> list[tuple[str, str]]:
    """(element type, name) of the elements of ``paths`` and the files they include."""
    queue = list(paths)
    seen: set[str] = set()
    found: list[tuple[str, str]] = []
    while queue and len(seen) < MAX_CONFIG_FILES:
        path = queue.pop(0)
        try:
            resolved = os.path.realpath(path)
            if resolved in seen:
                continue
            seen.add(resolved)
            text = _read_bounded(resolved)
        except (OSError, ValueError):
            continue
        elements, includes = scan_configuration(text)
        found += elements
        for raw in includes:
            target = _expand(raw)
            if not os.path.isabs(
                target
            ):  # beside the including file, else from the working directory
                beside = os.path.join(os.path.dirname(resolved), target)
                target = beside if os.path.isfile(beside) else os.path.abspath(target)
            queue.append(target)
    return found


def _printable(name: str) -> bool:
    return bool(name) and name.isprintable()


def element_candidates(words: list[str]) -> Iterator[str]:
    seen: set[str] = set()
    for element_type, name in configuration_elements(configuration_files(words)):
        if _printable(name) and name not in seen:
            seen.add(name)
            yield f"{name}\t{element_type}"


def input_candidates(words: list[str]) -> Iterator[str]:
    """Element names `monitor` and `serve` can select: devices, proxies and aliases."""
    for line in element_candidates(words):
        if line.rpartition("\t")[2] not in NOT_INPUT_TYPES:
            yield line


def keyboard_candidates(words: list[str]) -> Iterator[str]:
    for line in element_candidates(words):
        if line.endswith("\t" + _KEYBOARD_TYPE):
            yield line


SOURCES = {
    "drivers": driver_candidates,
    "emulators": emulator_candidates,
    "codes": code_candidates,
    "definitions": definition_candidates,
    "elements": element_candidates,
    "inputs": input_candidates,
    "keyboards": keyboard_candidates,
}


def main(argv: list[str]) -> int:
    """``__complete KIND [WORD...]``: print KIND's candidates for a line holding WORDs.
    Never fails loudly: a broken candidate source completes nothing."""
    if not argv or argv[0] not in SOURCES:
        print(f"gadgetctl: error: __complete takes one of {', '.join(KINDS)}", file=sys.stderr)
        return 2
    try:
        lines = list(SOURCES[argv[0]](argv[1:]))
    except Exception as err:  # completion must never print a traceback into a prompt
        if os.environ.get("GADGETCTL_DEBUG"):
            raise
        print(f"gadgetctl: completion failed: {type(err).__name__}: {err}", file=sys.stderr)
        return 1
    sys.stdout.write("".join(line + "\n" for line in lines))
    return 0
