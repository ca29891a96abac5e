"""Work `validate` spares (issue 27 goal 4) gives the results of doing it: the directory
walk finds what os.walk finds, and remembered suggestions are those difflib gives."""

from __future__ import annotations

import os
from difflib import get_close_matches
from pathlib import Path

from gadgetctl.files import JCCL_SUFFIXES, _jccl_files, is_file
from gadgetctl.suggest import close_names


def _walked(directory: Path) -> list[Path]:
    """What the walk gave before it listed directories itself (os.walk, a stat per file)."""
    found = []
    for parent, directories, names in os.walk(directory):
        directories[:] = [d for d in directories if not d.startswith(".")]
        found.extend(
            Path(parent, name)
            for name in names
            if not name.startswith(".")
            and Path(name).suffix in JCCL_SUFFIXES
            and is_file(Path(parent, name))
        )
    return sorted(found)


def test_the_walk_finds_what_os_walk_finds(tmp_path):
    for folder in ("a", "a/b", "a-c", ".hidden", "a/.git", "z"):
        (tmp_path / folder).mkdir()
    for name in (
        "a/one.jconf",
        "a/b/two.jdef",
        "a-c/three.jconf",
        ".hidden/no.jconf",
        "a/.git/no.jdef",
        "a/.dot.jconf",
        "z/x.jdef.bak",
        "z/X.JCONF",
        "z/several.dots.jconf",
    ):
        (tmp_path / name).write_text("<configuration/>")
    (tmp_path / "z" / "link.jconf").symlink_to(tmp_path / "a" / "one.jconf")
    (tmp_path / "z" / "dangling.jconf").symlink_to(tmp_path / "nowhere.jconf")
    (tmp_path / "z" / "folder.jconf").mkdir()
    (tmp_path / "z" / "linked").symlink_to(tmp_path / "a", target_is_directory=True)
    os.mkfifo(tmp_path / "z" / "pipe.jconf")
    found = _jccl_files(tmp_path)
    assert found == _walked(tmp_path)
    assert tmp_path / "z" / "link.jconf" in found
    assert tmp_path / "a-c" / "three.jconf" in found and tmp_path / "a/b/two.jdef" in found


def _difflib(word: str, names: list[str], cutoff: float = 0.6) -> list[str]:
    spelled: dict[str, str] = {}
    for name in names:
        spelled.setdefault(name.lower(), name)
    return [spelled[m] for m in get_close_matches(word.lower(), list(spelled), cutoff=cutoff)]


def test_remembered_suggestions_are_those_of_difflib():
    names = ["position_proxy", "digital_proxy", "analog_proxy", "Position_Proxy", "alias"]
    for _ in range(2):  # computed, then remembered
        assert close_names("positon_proxy", names) == _difflib("positon_proxy", names)
        assert close_names("ANALOG_PROXI", names) == _difflib("ANALOG_PROXI", names)
    assert close_names("positon_proxy", names)[0] == "position_proxy"
    shorter = names[1:]  # other candidates, another answer
    assert close_names("positon_proxy", shorter)[0] == "Position_Proxy"
    assert close_names("digital", iter(names), cutoff=0.5) == _difflib("digital", names, 0.5)


def test_a_shared_suggester_answers_as_a_fresh_one():
    from gadgetctl.suggest import CloseNames, shared_close_names

    names = ["Head Proxy", "Wand Proxy", "Head Tracker", "VJHead", "Wand"]
    shared = shared_close_names(names)
    assert shared_close_names(list(names)) is shared  # the same candidates: one suggester
    assert shared_close_names(names[1:]) is not shared
    for word in ("head proxi", "Wnd", "Head Trackr", "nothing like it"):
        assert shared(word, n=3, cutoff=0.7) == CloseNames(names)(word, n=3, cutoff=0.7)
        assert shared(word, n=3, cutoff=0.7) == _difflib(word, names, 0.7)
    many = [f"element {i}" for i in range(CloseNames.EXHAUSTIVE + 1)]
    assert shared_close_names(many) is not shared_close_names(many)  # never shared


def test_the_real_paths_found_on_the_walk_are_those_looked_up(tmp_path):
    from gadgetctl.files import real_path_text, resolved_paths

    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    (tmp_path / "a" / "one.jconf").write_text("<configuration/>")
    (tmp_path / "b" / "two.jconf").symlink_to(tmp_path / "a" / "one.jconf")
    (tmp_path / "b" / "three.jdef").write_text("<definition/>")
    (tmp_path / "linked").symlink_to(tmp_path / "b", target_is_directory=True)
    given = [tmp_path / "b", tmp_path / "a", tmp_path / "linked" / "three.jdef"]
    found = resolved_paths(given)
    assert [(p, real) for p, real in found] == [(p, real_path_text(str(p))) for p, _ in found]
    # b/two.jconf is a/one.jconf, and linked/three.jdef is b/three.jdef: each file once
    assert [p.name for p, _ in found] == ["three.jdef", "two.jconf"]


def test_embedded_elements_come_depth_first_as_before(tmp_path):
    from gadgetctl.jccl.configload import load_configuration

    from conftest import write
    from jccl_samples import jconf

    def recursive(element):  # what embedded() was: nested generators
        for values in element.property_values():
            for value in values:
                if value.element is not None:
                    yield value.element
                    yield from recursive(value.element)

    def nested(name: str, depth: int) -> str:
        inner = nested(f"{name}.{depth}", depth - 1) if depth else "<x>1</x>"
        return f'<group name="{name}" version="1"><a>{inner}</a><b>text</b><a>{inner}</a></group>'

    elements = "".join(nested(f"g{i}", depth) for i, depth in enumerate((0, 1, 3)))
    config = load_configuration([write(tmp_path / "n.jconf", jconf(elements))])
    for element in config.elements:
        assert [e.name for e in element.embedded()] == [e.name for e in recursive(element)]
    deepest = config.elements[-1]
    assert len(list(deepest.embedded())) == 2 + 4 + 8 + 16
    element = config.elements[-1]
    element.properties = dict(element.properties)  # the dict form too
    assert [e.name for e in element.embedded()] == [e.name for e in recursive(element)]
