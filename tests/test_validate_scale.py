"""Validation and `config graph` stay linear on long chains and many findings (issue 13
item 7): chain walks shared, "did you mean" indexed, columns from one scan per line, graph
edges indexed and drawn without recursion.

Timings live in `bench/bench_validate_scale.py`; the timeouts here only guard against a
hang (each case took minutes or crashed before).
"""

from __future__ import annotations

import random
import subprocess
import sys
from difflib import SequenceMatcher, get_close_matches

import pytest

from gadgetctl.diagnostics import Severity
from gadgetctl.jccl.graph import CONTAINS, POINTER, Edge, Node, WiringGraph, render_text
from gadgetctl.suggest import CloseNames
from gadgetctl.validate import ValidateOptions, validate_paths

HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="scale">\n<elements>\n'
)
TAIL = "</elements>\n</configuration>\n"


def alias_chain(count: int, end: str = "Nowhere") -> str:
    """Alias i points at alias i - 1; alias 0 at ``end``."""
    return "".join(
        f'<alias name="A{i}" version="1"><proxy>{end if i == 0 else f"A{i - 1}"}</proxy></alias>\n'
        for i in range(count)
    )


def ratio(word: str, name: str) -> float:
    matcher = SequenceMatcher()
    matcher.set_seq2(word)
    matcher.set_seq1(name)
    return matcher.ratio()


def by_code(diagnostics, code):
    return [d for d in diagnostics if d.code == code]


@pytest.mark.timeout(300)
def test_a_50000_alias_chain_is_reported_once_at_its_head_with_a_count(tmp_path):
    """Each alias names the one before (an alias, where a proxy is wanted) and waits for it:
    one problem, reported at the head of the chain with the number of aliases behind it and
    where the chain ends, not 50,000 times over."""
    count = 50_000
    path = tmp_path / "chain.jconf"
    path.write_text(HEAD + alias_chain(count) + TAIL)
    result = validate_paths([path], ValidateOptions())
    assert sorted(d.code for d in result.diagnostics) == ["CFG031", "CFG032", "CFG041"]
    (missing,) = by_code(result.diagnostics, "CFG031")
    (wrong,) = by_code(result.diagnostics, "CFG032")
    (pending,) = by_code(result.diagnostics, "CFG041")
    assert "alias 'A0'" in missing.message and missing.line == 5
    for head in (wrong, pending):  # alias A1's <proxy> tag, after four head lines
        assert head.message.startswith("alias 'A1'") and (head.line, head.column) == (6, 30)
        assert f"{count - 2} more alias elements chained behind it" in head.message
        assert f"the last is alias 'A{count - 1}' at {path}:{count + 4}:1" in head.message
    assert "proxy 'A0' is an alias (at" in wrong.message  # not "a alias"
    # The chain ends at a name no element of this file has, which another file loaded with
    # it could provide: a warning, as at its end.
    assert pending.severity is Severity.WARNING and wrong.severity is Severity.ERROR


@pytest.mark.timeout(300)
def test_validate_command_on_a_long_alias_chain_ends_with_findings_not_an_internal_error(tmp_path):
    path = tmp_path / "chain.jconf"
    path.write_text(HEAD + alias_chain(5_000) + TAIL)
    done = subprocess.run(
        [sys.executable, "-m", "gadgetctl", "validate", str(path), "-f", "json"],
        capture_output=True,
        text=True,
        timeout=280,
    )
    assert done.returncode == 1, done.stderr
    assert "internal error" not in done.stderr and "Traceback" not in done.stderr
    assert done.stdout.count('"CFG041"') == 1 and done.stdout.count('"CFG032"') == 1
    assert done.stdout.count("4998 more alias elements chained behind it") == 2


def test_chains_fold_into_their_heads_and_branches_are_not_lost(tmp_path):
    """A chain folds only while each element is of the head's type and repeats its problem:
    a branch folds into the same head, a proxy pointing into the chain keeps its own finding,
    and a cycle gets one head."""
    elements = (
        '<alias name="B0" version="1"><proxy>Nowhere</proxy></alias>\n'
        '<alias name="B1" version="1"><proxy>B0</proxy></alias>\n'
        '<alias name="B2" version="1"><proxy>B1</proxy></alias>\n'
        '<alias name="B3" version="1"><proxy>B1</proxy></alias>\n'  # a branch of the chain
        '<analog_proxy name="Q" version="1"><device>B3</device><unit>0</unit></analog_proxy>\n'
        '<alias name="C0" version="1"><proxy>C1</proxy></alias>\n'  # a cycle of three
        '<alias name="C1" version="1"><proxy>C2</proxy></alias>\n'
        '<alias name="C2" version="1"><proxy>C0</proxy></alias>\n'
    )
    path = tmp_path / "branches.jconf"
    path.write_text(HEAD + elements + TAIL)
    found = validate_paths([path], ValidateOptions()).diagnostics
    pending = {d.message.split("'")[1]: d.message for d in by_code(found, "CFG041")}
    wrong = {d.message.split("'")[1]: d.message for d in by_code(found, "CFG032")}
    assert "2 more alias elements chained behind it" in pending["B1"]
    assert set(pending) == {
        "B1",
        "C0",
    }  # B2 and B3 behind B1; C1 and C2 behind C0 (a proxy never waits)
    assert "2 more alias elements" in pending["C0"]
    assert set(wrong) == {"B1", "Q", "C0"}
    assert "2 more alias elements" in wrong["B1"] and "more" not in wrong["Q"]


def test_fold_chains_gives_every_key_one_head():
    from gadgetctl.jccl.chains import fold_chains

    # 1 and 3 follow 0 and 2 follows 1 (a branch); 4 and 5 follow each other (a cycle); 6's
    # leader is not among the positions
    heads = fold_chains(7, {1: 0, 2: 1, 3: 0, 4: 5, 5: 4, 6: 99})
    assert {head: list(followers) for head, followers in heads.items()} == {
        0: [1, 3, 2],
        6: [],
        4: [5],
    }
    assert list(heads) == [0, 6, 4]


@pytest.mark.timeout(300)
def test_many_dangling_pointers_get_the_right_suggestions_and_columns_on_one_line(tmp_path):
    """8,000 proxies on one line, each pointing at a device name with one typo, next to
    8,000 devices: every pointer is reported at its own <device> tag, and the name it was
    meant to be is the first suggestion."""
    count = 8_000
    rng = random.Random(7)
    devices = [f"Tracker {i:04d}" for i in range(count)]
    typos = {}
    parts = []
    for i, name in enumerate(devices):
        cut = rng.randrange(len(name))
        typo = name[:cut] + name[cut + 1 :]  # one letter dropped
        typos[f"P{i}"] = (typo, name)
        parts.append(
            f'<waveform_device name="{name}" version="1"><rate>60.0</rate></waveform_device>'
        )
        parts.append(
            f'<analog_proxy name="P{i}" version="1"><device>{typo}</device><unit>0</unit></analog_proxy>'
        )
    text = (HEAD + "".join(parts) + TAIL).replace("\n", " ")
    path = tmp_path / "dangling.jconf"
    path.write_text(text)
    result = validate_paths([path], ValidateOptions())
    dangling = by_code(result.diagnostics, "CFG031")
    existing = set(devices)
    checked = exact = 0
    for diagnostic in dangling:
        proxy = diagnostic.message.split("'")[1]
        typo, meant = typos[proxy]
        assert typo not in existing
        assert diagnostic.line == 1
        assert text[diagnostic.column - 1 :].startswith(f"<device>{typo}</device>"), (
            proxy,
            diagnostic.column,
        )
        # The first suggestion is as close as the name meant (a dropped digit can make
        # several names equally close; then difflib's order among them is kept).
        assert diagnostic.hint is not None and diagnostic.hint.startswith("Did you mean '"), (
            diagnostic.hint
        )
        first = diagnostic.hint.split("'")[1]
        assert ratio(typo, first) >= ratio(typo, meant), (typo, first, meant)
        exact += first == meant
        checked += 1
    assert checked > count * 0.9  # (a typo can happen to spell another device's name)
    assert exact > checked * 0.5
    element_columns = [d for d in result.diagnostics if d.code == "CFG034"]
    for diagnostic in element_columns[:50]:
        assert text[diagnostic.column - 1 :].startswith("<analog_proxy name="), diagnostic


def test_indexed_suggestions_agree_with_difflib():
    rng = random.Random(3)
    names = (
        [f"Wave {i} Position" for i in range(3000)]
        + [f"Tracker {i:04d}" for i in range(1500)]
        + ["VJWand", "VJHead", "VJButton0", "Head Proxy", "Wand Proxy"]
    )
    index = CloseNames(names, ignore_case=False)

    def typo(name: str) -> str:
        cut = rng.randrange(len(name))
        letter = rng.choice("abcdefghij0123456789 ")
        return rng.choice(
            [
                name[:cut] + name[cut + 1 :],
                name[:cut] + letter + name[cut:],
                name[:cut] + letter + name[cut + 1 :],
            ]
        )

    words = [typo(rng.choice(names)) for _ in range(60)] + [
        "VJWnd",
        "Head Prxy",
        "nothing like it at all",
    ]
    for word in words:
        ours = index(word, n=3, cutoff=0.7)
        theirs = get_close_matches(word, names, n=3, cutoff=0.7)
        assert ours[:1] == theirs[:1], word  # the best suggestion is difflib's
        assert len(ours) == len(theirs), word
        for name in ours:
            assert name in names and SequenceMatcher(None, word, name).ratio() >= 0.7
    few = CloseNames(["Head Proxy", "Wand Proxy", "VJWand"], ignore_case=False)
    assert few("Wand Prxy", n=3, cutoff=0.6) == get_close_matches(
        "Wand Prxy", ["Head Proxy", "Wand Proxy", "VJWand"], n=3, cutoff=0.6
    )
    assert CloseNames(["Waveform Sticks"])("waveform stick") == ["Waveform Sticks"]


def _chain_graph(links: int) -> WiringGraph:
    graph = WiringGraph()
    for i in range(links):
        graph.nodes[f"n{i}"] = Node(f"n{i}", "alias", "alias", f"A{i}")
    for i in range(1, links):
        graph.edges.append(Edge(f"n{i}", f"n{i - 1}", POINTER, "proxy"))
    return graph


@pytest.mark.timeout(120)
def test_graph_text_of_a_long_alias_chain_shows_every_alias_without_recursion():
    links = 20_000
    text = render_text(_chain_graph(links))
    lines = text.splitlines()
    continued = sum("(continued below)" in line for line in lines)
    assert continued == (links - 2) // 64  # every 64 levels, the chain goes on as a new tree
    assert len(lines) == links + continued  # (where it goes on, the alias is shown again)
    assert all(f"alias 'A{i}'" in text for i in (0, 1, links // 2, links - 1))
    assert lines[0] == f"alias 'A{links - 1}'"
    assert max(len(line) for line in lines) < 400


@pytest.mark.timeout(120)
def test_graph_text_of_many_elements_is_drawn_from_an_edge_index():
    """30,000 devices with an embedded filter each: scanning every edge per node (the old
    outgoing()) took minutes."""
    graph = WiringGraph()
    for i in range(30_000):
        graph.nodes[f"d{i}"] = Node(f"d{i}", "device", "waveform_device", f"W{i}")
        graph.nodes[f"f{i}"] = Node(f"f{i}", "element", "position_transform_filter", f"W{i}/F")
        graph.edges.append(Edge(f"d{i}", f"f{i}", CONTAINS, "position_filters"))
    lines = render_text(graph).splitlines()
    assert len(lines) == 60_000
    assert lines[:2] == [
        "waveform_device 'W0'",
        "└── position_filters contains position_transform_filter 'W0/F'",
    ]


def test_the_near_index_answers_as_difflib_or_leaves_it_to_the_bounded_pass():
    """Past the first questions, answers come from the candidates one edit away when they
    prove the best match (no other candidate can be as close): then the first suggestion is
    difflib's first and as many are given as difflib gives."""
    rng = random.Random(11)
    names = [f"Tracker {i:05d}" for i in range(6000)] + [f"Wave {i} Position" for i in range(2000)]
    index = CloseNames(names, ignore_case=False)
    index.NEAR_AFTER = 0
    answered = 0
    for _ in range(150):
        name = rng.choice(names)
        cut = rng.randrange(len(name))
        word = rng.choice([name[:cut] + name[cut + 1 :], name[:cut] + "x" + name[cut + 1 :]])
        ours = index._nearby(word, *index._window(len(word), 0.7), 3, 0.7)
        if ours is None:
            continue
        answered += 1
        theirs = get_close_matches(word, names, n=3, cutoff=0.7)
        assert ours[:1] == theirs[:1] and len(ours) == len(theirs), word
        assert all(ratio(word, found) >= 0.7 for found in ours)
    # most: a changed letter next to names two letters longer is left to the bounded pass
    assert answered > 75
