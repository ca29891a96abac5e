"""Shell completion scripts: up to date with the CLI, and working in bash."""

from __future__ import annotations

import subprocess

import pytest

from gadgetctl.cli.completions import FILES, scripts

from conftest import REPO, require_tool


def test_completion_files_are_up_to_date():
    current = scripts()
    for shell, name in FILES.items():
        stale = (REPO / "completions" / name).read_text(encoding="utf-8") != current[shell]
        assert not stale, f"completions/{name} is stale: run `make completions`"


def _bash_complete(*words: str) -> list[str]:
    script = REPO / "completions" / FILES["bash"]
    array = " ".join(f"'{w}'" for w in ("gadgetctl", *words))
    cmd = (f"source '{script}'; COMP_WORDS=({array}); COMP_CWORD={len(words)}; _gadgetctl; "
           'printf "%s\\n" "${COMPREPLY[@]}"')
    out = subprocess.run(["bash", "-c", cmd], capture_output=True, text=True, timeout=10, check=True)
    return [line for line in out.stdout.splitlines() if line]


def test_bash_completes_commands_options_and_choices():
    assert "validate" in _bash_complete("")
    assert _bash_complete("defs", "sh") == ["show"]
    assert _bash_complete("validate", "--format", "") == ["text", "json", "github", "sarif"]
    assert "--no-bundled" in _bash_complete("validate", "--no")


@pytest.mark.parametrize("shell", ["zsh", "fish"])
def test_other_shells_parse_the_scripts(shell, tmp_path):
    require_tool(shell, shell)
    path = REPO / "completions" / FILES[shell]
    flag = ["-n"] if shell == "zsh" else ["--no-execute"]
    subprocess.run([shell, *flag, str(path)], check=True, timeout=10)


def test_completion_command_prints_the_script(cli):
    assert cli("completion", "fish").stdout == scripts()["fish"]
