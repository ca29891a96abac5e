"""Every `$ gadgetctl ...` example in README.md runs with the exit code it documents."""

from __future__ import annotations

import re
import shlex

import pytest

from conftest import REPO

EXAMPLE = re.compile(r"^\$ (gadgetctl .*?)(?:\s+#\s*exit (\d+))?$")


DOCUMENTS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]


def readme_examples() -> list[tuple[str, int]]:
    """``$ gadgetctl`` lines of ```console blocks in the README and docs/ (not ```sh ones)."""
    examples = []
    for document in DOCUMENTS:
        examples += _examples(document)
    return examples


def _examples(document) -> list[tuple[str, int]]:
    examples = []
    in_console = False
    for line in document.read_text(encoding="utf-8").splitlines():
        if line.startswith("```"):
            in_console = line.strip() == "```console"
            continue
        match = EXAMPLE.match(line) if in_console else None
        if match:
            examples.append((match.group(1), int(match.group(2) or 0)))
    return examples


def test_readme_has_examples():
    assert len(_examples(REPO / "README.md")) >= 20


@pytest.mark.parametrize(("command", "expected"), readme_examples(), ids=lambda v: str(v)[:60])
def test_readme_example(command, expected, cli, corpus):
    args = shlex.split(command)[1:]
    result = cli(*args, cwd=REPO)
    assert result.exit_code == expected, f"{command}\n{result.stdout[-2000:]}\n{result.stderr}"
    assert "Traceback" not in result.stderr
