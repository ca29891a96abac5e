"""Shell completion scripts: up to date with the CLI, and working in bash."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

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
    cmd = (
        f"source '{script}'; COMP_WORDS=({array}); COMP_CWORD={len(words)}; _gadgetctl; "
        'printf "%s\\n" "${COMPREPLY[@]}"'
    )
    out = subprocess.run(
        ["bash", "-c", cmd], capture_output=True, text=True, timeout=10, check=True
    )
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


# --- dynamic completion: `gadgetctl __complete KIND WORDS...` and the three shells ---------

SIM = (
    "../shared/corpus/vrjuggler/modules/vrjuggler/data/configFiles/sim.base.jconf",
    "../shared/corpus/vrjuggler/modules/vrjuggler/data/configFiles/sim.wand.mixin.jconf",
)
BIN = Path(sys.executable).parent
SHELL_ENV = {"PATH": f"{BIN}{os.pathsep}/usr/bin{os.pathsep}/bin", "LANG": "C.UTF-8"}

WAVEFORM_AND_FRIENDS = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="friends">
   <include>included.jconf</include>
   <elements>
      <!-- <waveform_device name="Commented Out" version="1"/> -->
      <waveform_device name="Wave &amp; Sticks" version="1">
         <position_filters>
            <position_transform_filter name="Inner Filter" version="1"/>
         </position_filters>
      </waveform_device>
      <keyboard_mouse_device name='Only Keyboard' version="2"/>
      <user name="Somebody" version="1"/>
   </elements>
</configuration>
"""
INCLUDED = """<?xml version="1.0" encoding="UTF-8"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="included">
   <elements><alias name="From Include" version="1"><proxy>x</proxy></alias></elements>
</configuration>
"""


def _complete(*args: str, cwd: Path = REPO) -> list[str]:
    done = subprocess.run(
        [sys.executable, "-m", "gadgetctl", "__complete", *args],
        capture_output=True,
        text=True,
        timeout=30,
        cwd=cwd,
        check=True,
    )
    return done.stdout.splitlines()


def _names(lines: list[str]) -> list[str]:
    return [line.partition("\t")[0] for line in lines]


@pytest.fixture
def friends(tmp_path) -> Path:
    (tmp_path / "included.jconf").write_text(INCLUDED, encoding="utf-8")
    path = tmp_path / "friends.jconf"
    path.write_text(WAVEFORM_AND_FRIENDS, encoding="utf-8")
    return path


def test_element_names_come_from_the_configurations_on_the_line(friends):
    lines = _complete("elements", "config", "show", str(friends), "--element")
    assert _names(lines) == ["Wave & Sticks", "Only Keyboard", "Somebody", "From Include"]
    assert "Wave & Sticks\twaveform_device" in lines
    assert _names(_complete("inputs", "monitor", str(friends))) == [
        "Wave & Sticks",
        "Only Keyboard",
        "From Include",
    ]
    assert _names(_complete("keyboards", "monitor", str(friends), "--keyboard")) == [
        "Only Keyboard"
    ]
    assert _complete("elements", "config", "show", "--element") == []  # no configuration yet


def test_element_scan_reads_a_bounded_prefix(tmp_path):
    from gadgetctl.cli.candidates import MAX_CONFIG_BYTES

    big = tmp_path / "big.jconf"
    head = '<configuration><elements><alias name="Early" version="1"/>'
    big.write_text(
        head
        + " " * MAX_CONFIG_BYTES
        + '<alias name="Late" version="1"/></elements></configuration>'
    )
    assert _names(_complete("elements", str(big))) == ["Early"]


def test_driver_emulator_code_and_definition_candidates(tmp_path):
    plugins = tmp_path / "plugins"
    (plugins / "Acme_drv").mkdir(parents=True)
    (plugins / "Acme_drv" / "__init__.py").write_text("PLUGIN_NAME = 'Acme_drv'\n")
    (plugins / "Acme_drv" / "acme_wand.jdef").write_text('<definition name="acme_wand"/>\n')
    (plugins / "Loose_drv.py").write_text("")
    (plugins / "test_helpers.py").write_text("")
    drivers = _names(_complete("drivers", "drivers", "load", "--driver-path", str(plugins)))
    assert {"DTrack_drv", "Flock_drv", "Acme_drv", "Loose_drv"} <= set(drivers)
    assert "test_helpers" not in drivers
    emulators = _names(_complete("emulators", "emulate", f"--driver-path={plugins}"))
    assert "DTrack_drv" in emulators and "Acme_drv" not in emulators  # Acme ships no emulator.py

    from gadgetctl.diagnostics import all_codes

    codes = _complete("codes", "explain")
    assert codes == [
        f"{c.code}\t{c.title}" for c in sorted(all_codes().values(), key=lambda c: c.code)
    ]

    defs = tmp_path / "defs"
    defs.mkdir()
    (defs / "odd_file_name.jdef").write_text(
        '<?xml version="1.0"?>\n<definition xmlns="x" name="my_tracker">\n'
    )
    names = _names(_complete("definitions", "defs", "show", "-d", str(defs)))
    assert {"dtrack", "alias", "my_tracker"} <= set(names)
    assert "odd_file_name" not in names
    only = _names(
        _complete(
            "definitions",
            "defs",
            "show",
            "--no-bundled",
            "--driver-path",
            str(plugins),
            "--definitions",
            str(defs),
        )
    )
    assert "my_tracker" in only and "acme_wand" in only and "dtrack" not in only


def test_not_input_types_are_the_bundled_definitions_outside_devices_and_proxies():
    from gadgetctl.cli.candidates import NOT_INPUT_TYPES

    outside = set()
    for path in (REPO / "definitions").glob("*.jdef"):
        categories = re.findall(r"<category>([^<]*)</category>", path.read_text(encoding="utf-8"))
        if categories and not any(c.startswith(("/Devices", "/Proxies")) for c in categories):
            outside.add(path.stem)
    assert outside == NOT_INPUT_TYPES


def test_completing_loads_no_heavy_library(friends):
    code = (
        "import sys\nfrom gadgetctl.cli.main import main\n"
        "for kind in ('inputs', 'drivers', 'definitions', 'codes'):\n"
        "    try:\n        main(['__complete', kind, 'monitor', sys.argv[1]])\n"
        "    except SystemExit:\n        pass\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in "
        "('typer', 'click', 'rich', 'lxml', 'numpy', 'xmlschema', 'dataclasses_json')), file=sys.stderr)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code, str(friends)],
        capture_output=True,
        text=True,
        timeout=30,
        check=True,
    )
    assert done.stderr.strip() == "[]"


def test_unknown_kind_is_a_usage_error(cli):
    result = cli("__complete", "nonsense")
    assert result.exit_code == 2 and "__complete takes one of" in result.stderr


def _bash(*words: str, cwd: Path = REPO) -> list[str]:
    script = REPO / "completions" / FILES["bash"]
    array = " ".join(shlex.quote(w) for w in ("gadgetctl", *words))
    cmd = (
        f"source '{script}'; COMP_WORDS=({array}); COMP_CWORD={len(words)}; _gadgetctl; "
        'printf "%s\\n" "${COMPREPLY[@]}"'
    )
    out = subprocess.run(
        ["bash", "-c", cmd],
        capture_output=True,
        text=True,
        timeout=30,
        check=True,
        env=SHELL_ENV,
        cwd=cwd,
    )
    return [line for line in out.stdout.splitlines() if line]


def test_bash_completes_dynamic_words(friends):
    assert _bash("explain", "XML00") == ["XML001", "XML002", "XML003", "XML004", "XML005"]
    assert _bash("emulate", "DTr") == ["DTrack_drv"]
    assert "DTrack_drv" not in _bash(
        "emulate", "DTrack_drv", "DTr"
    )  # DRIVER given: the emulator's words
    assert _bash("defs", "show", "dtra") == ["dtrack"]
    assert _bash("defs", "list", "--base", "positional_d") == ["positional_device"]
    assert _bash("drivers", "load", "Flock_drv", "Fla") == []
    assert _bash("drivers", "load", "Flock_drv", "Fa") == ["Fastrak_drv"]
    assert _bash("monitor", *SIM, "--keyboard", "") == [
        "Head Keyboard",
        "Sim View Cameras Keyboard",
        "Wand Keyboard",
    ]
    assert _bash("monitor", "--rate", "30", *SIM, "Wand") == [
        "Wand Proxy",
        "Wand Keyboard",
        "Wand Input Window",
        "Wand Keyboard Proxy",
    ]
    assert _bash("config", "show", str(friends), "--element", "Wave\\ &") == ["Wave & Sticks"]
    assert _bash("config", "show", "-e", "Only") == []  # no configuration on the line
    plugins = friends.parent / "plugins"
    (plugins / "Acme_drv").mkdir(parents=True)
    (plugins / "Acme_drv" / "__init__.py").write_text("")
    (plugins / "Acme_drv" / "emulator.py").write_text("")
    # bash splits --driver-path=DIR at the `=` (COMP_WORDBREAKS)
    assert _bash("emulate", "--driver-path", "=", str(plugins), "Acm") == ["Acme_drv"]
    assert _bash("monitor", *SIM, "--keyboard", "=", "Wa") == ["Wand Keyboard"]


def _fish(line: str) -> list[str]:
    require_tool("fish", "fish")
    script = REPO / "completions" / FILES["fish"]
    out = subprocess.run(
        [
            "fish",
            "--no-config",
            "-c",
            f"source {shlex.quote(str(script))}; complete -C $argv[1]",
            line,
        ],
        capture_output=True,
        text=True,
        timeout=30,
        check=True,
        env=SHELL_ENV,
        cwd=REPO,
    )
    return out.stdout.splitlines()


def test_fish_completes_dynamic_words_with_descriptions(friends):
    assert _fish("gadgetctl explain XML00")[0] == "XML001\tXML is not well-formed"
    assert [line.partition("\t")[0] for line in _fish("gadgetctl emulate DTr")] == ["DTrack_drv"]
    assert not any(
        line.startswith("DTrack_drv") for line in _fish("gadgetctl emulate DTrack_drv DTr")
    )
    assert "dtrack" in [line.partition("\t")[0] for line in _fish("gadgetctl defs show dtr")]
    keyboards = _fish(f"gadgetctl monitor {' '.join(SIM)} --keyboard ")
    assert keyboards == [
        "Head Keyboard\tkeyboard_mouse_device",
        "Sim View Cameras Keyboard\tkeyboard_mouse_device",
        "Wand Keyboard\tkeyboard_mouse_device",
    ]
    names = [line.partition("\t")[0] for line in _fish(f"gadgetctl monitor {' '.join(SIM)} SimCam")]
    assert names == ["SimCam1 Proxy", "SimCam2 Proxy", "SimCamera1", "SimCamera2"]
    elements = _fish(f"gadgetctl config show {friends} --element Wave")
    assert elements == ["Wave & Sticks\twaveform_device"]


@pytest.mark.timeout(120)
def test_zsh_completes_dynamic_words_at_a_real_prompt(tmp_path, friends):
    """An interactive zsh in a tmux pane, with compinit and the script on $fpath: Tab."""
    require_tool("zsh", "zsh")
    from tmux_pane import Pane

    setup = (
        f"fpath=({shlex.quote(str(REPO / 'completions'))} $fpath); autoload -U compinit; "
        "compinit -u -D; PS1='READY%% '"
    )
    command = (
        f"env -i HOME={shlex.quote(str(tmp_path))} PATH={shlex.quote(SHELL_ENV['PATH'])} TERM=xterm "
        "zsh -f"
    )
    with Pane(command, cols=320, rows=40) as pane:
        pane.wait_for(r"[#%>]\s*$")  # zsh's own prompt: it reads the line from now on
        pane.keys(setup, "Enter")
        pane.wait_for(r"^READY%\s*$")
        pane.keys("gadgetctl explain XML00", literal=True)
        pane.keys("Tab")
        pane.wait_for(r"^XML004\s+-- file too large")
        pane.keys("C-u", "clear", "Enter")
        pane.wait_for(r"^READY%\s*$")
        pane.keys("gadgetctl emulate DTr", literal=True)
        pane.keys("Tab")
        pane.wait_for(r"^READY% gadgetctl emulate DTrack_drv\s*$")
        pane.keys("C-u", "clear", "Enter")
        pane.wait_for(r"^READY%\s*$")
        pane.keys(f"gadgetctl config show {friends} --element Wa", literal=True)
        pane.keys("Tab")
        pane.wait_for(r"--element Wave\\ \\&\\ Sticks\s*$")
        pane.keys("C-u", "clear", "Enter")
        pane.wait_for(r"^READY%\s*$")
        pane.keys(f"gadgetctl monitor {' '.join(SIM)} --keyboard W", literal=True)
        pane.keys("Tab")
        pane.wait_for(r"--keyboard Wand\\ Keyboard\s*$")
