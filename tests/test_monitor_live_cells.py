"""The live view's cells in real terminals (tmux; issue 25 item 5): glove values are left out
a finger at a time, never cut; a name longer than the name column keeps the columns in line;
position rows keep the type column where the other rows do; and the statistics printed on
quitting fit an 80-column terminal instead of wrapping."""

from __future__ import annotations

import re
import shlex
import sys

import pytest
from tmux_pane import Pane

from conftest import REPO

pytestmark = pytest.mark.timeout(90)

LONG = "Left Glove Proxy of the Second Lab"  # 34 characters, over the 22 of the old column
SHOWN = ("Sim Glove", LONG, "Right Glove Proxy", "Head Proxy", "Button 0 Proxy", "Left Index Proxy")
FINGER = r"(?:thumb|index|middle|ring|pinky|wrist) -?\d+/-?\d+/-?\d+/-?\d+"


def command(tmp_path) -> str:
    text = (REPO / "examples" / "all_devices.jconf").read_text(encoding="utf-8")
    config = tmp_path / "lab.jconf"
    config.write_text(text.replace("Left Glove Proxy", LONG), encoding="utf-8")
    args = (sys.executable, "-m", "gadgetctl", "monitor", config, *SHOWN, "--no-mouse")
    return " ".join(shlex.quote(str(a)) for a in args)


def proxy_lines(pane: Pane) -> dict[str, str]:
    pane.wait_for(r"^  Left Index Proxy\s.*active")
    lines = pane.screen().splitlines()
    return {
        name: next(line for line in lines if line.startswith(f"  {name[:20]}"))
        for name in SHOWN[1:]
    }


@pytest.mark.parametrize(("cols", "rows"), [(80, 24), (120, 40)])
def test_cells_are_whole_and_columns_in_line(tmp_path, cols, rows):
    with Pane(command(tmp_path), cols=cols, rows=rows) as pane:
        pane.wait_for(rf"^  {LONG}\s+.*active\s+thumb")
        lines = proxy_lines(pane)
        for name in (LONG, "Right Glove Proxy"):  # every finger shown is whole
            assert re.search(rf"active\s+{FINGER}( {FINGER})*$", lines[name].rstrip()), lines[name]
        glove_rows = [line for line in pane.screen().splitlines() if line.startswith("    glove ")]
        assert glove_rows and all(re.search(rf"{FINGER}$", row.rstrip()) for row in glove_rows)
        # the state column starts at the same place on every row, the long name's included
        assert len({line.index(" active") for line in lines.values()}) == 1, lines
        typed = ["proxy →" in line for line in lines.values()]
        assert all(typed) or not any(typed), lines  # the type column for all rows or none
        if cols >= 120:
            assert all(typed)
        pane.keys("q", literal=True)
        pane.wait_for(r"EXIT=\d")
        joined = pane._run("capture-pane", "-p", "-J", "-t", "t").splitlines()
    start = joined.index("statistics:")
    table = joined[start + 1 : start + 6]
    assert table[0].startswith("DEVICE") and table[1].startswith("Sim Glove")
    assert all(len(line) <= cols for line in table), table
