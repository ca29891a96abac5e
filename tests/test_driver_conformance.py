"""Every driver has conformance tests fed by a source other than its emulator, and the README
says, per driver, what that source is (issue "Readings you can trust")."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DRIVERS = sorted(p.name for p in (ROOT / "drivers").iterdir() if p.name.endswith("_drv"))


def readme_rows() -> dict[str, list[str]]:
    rows: dict[str, list[str]] = {}
    for line in (ROOT / "README.md").read_text(encoding="utf-8").splitlines():
        match = re.match(r"\| `(\w+_drv)` \|", line)
        if match:
            rows[match.group(1)] = [cell.strip() for cell in line.strip("|").split(" | ")]
    return rows


def test_there_are_twenty_drivers() -> None:
    assert len(DRIVERS) == 20


@pytest.mark.parametrize("driver", DRIVERS)
def test_each_driver_has_conformance_tests_that_name_their_source(driver: str) -> None:
    path = ROOT / "drivers" / driver / "tests" / "test_conformance.py"
    assert path.is_file(), f"{driver} has no tests/test_conformance.py"
    module = ast.parse(path.read_text(encoding="utf-8"))
    doc = ast.get_docstring(module) or ""
    assert re.search(r"\bsources?\b", doc, re.IGNORECASE) or "spec" in doc.lower(), (
        f"{driver}'s conformance tests do not say where their bytes come from"
    )
    tests = [
        node.name
        for node in module.body
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
        and node.name.startswith("test_")
    ]
    assert tests, f"{driver}'s conformance module holds no test"


def test_the_readme_table_says_what_each_driver_is_checked_against() -> None:
    rows = readme_rows()
    assert sorted(rows) == DRIVERS
    for driver, cells in rows.items():
        assert len(cells) == 5, f"{driver}: {cells}"
        assert len(cells[4]) > 20, f"{driver}: no conformance source in the README"
