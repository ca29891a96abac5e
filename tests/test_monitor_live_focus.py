"""Keyboard focus in the live view (issue 16 item 2), in a real terminal (tmux): one
keyboard_mouse_device gets the keys at a time, Tab moves the focus, ``--keyboard`` chooses it,
every key keeps the modifiers it was typed with even when several arrive in one frame, and
one Esc cancels the marker prompt.
"""

from __future__ import annotations

import shlex
import subprocess
import sys

import pytest
from tmux_pane import Pane

from gadgetctl.input.events import KeyEvent
from gadgetctl.input.keys import Key, Modifier
from gadgetctl.input.sim.keyboard import KeyboardMouseDevice

from conftest import REPO

pytestmark = pytest.mark.timeout(90)

CONFIGS = (
    REPO.parent
    / "shared"
    / "corpus"
    / "vrjuggler"
    / "modules"
    / "vrjuggler"
    / "data"
    / "configFiles"
)
SIM_BASE = CONFIGS / "sim.base.jconf"
SIM_WAND = CONFIGS / "sim.wand.mixin.jconf"
ALL_DEVICES = REPO / "examples" / "all_devices.jconf"
POSITION = r"position 0\s+x (\S+) y (\S+) z (\S+) m\s+rot\s+(\S+)\s+(\S+)\s+(\S+)°"


def monitor(*args: object) -> str:
    return " ".join(
        shlex.quote(str(a)) for a in (sys.executable, "-m", "gadgetctl", "monitor", *args)
    )


def position_of(pane: Pane, device: str) -> tuple[str, ...]:
    """The position line under ``device``'s row, as text fields."""
    return pane.wait_for(rf"^{device}\s.*\n\s+{POSITION}").groups()


def wait_position(pane: Pane, device: str, expected: tuple[str, ...]) -> None:
    pane.wait_for(
        rf"^{device}\s.*\n\s+position 0\s+x {expected[0]} y {expected[1]} z {expected[2]} m"
        rf"\s+rot\s+{expected[3]}\s+{expected[4]}\s+{expected[5]}°"
    )


def test_keys_go_to_the_focused_keyboard_only_and_tab_moves_the_focus():
    command = monitor(
        SIM_BASE, SIM_WAND, "SimHeadPos", "SimCamera1", "SimCamera2", "--no-mouse", "--rate", "10"
    )
    with Pane(command, cols=200, rows=40) as pane:
        pane.wait_for(r"other keys and the mouse → Head Keyboard\s+\(Tab: next of 3 keyboards\)")
        head, camera1, camera2 = (
            position_of(pane, d) for d in ("SimHeadPos", "SimCamera1", "SimCamera2")
        )
        assert head[:3] == ("+0.000", "+1.829", "+0.000")
        pane.keys(
            "8", literal=True
        )  # Forward of SimHeadPos and SimCamera1: only the head's keyboard has focus
        wait_position(
            pane, "SimHeadPos", ("\\+0.000", "\\+1.829", "-0.005", "\\+0.0", "\\+0.0", "\\+0.0")
        )
        assert position_of(pane, "SimCamera1") == camera1
        pane.keys("Tab")
        pane.wait_for(r"other keys and the mouse → Sim View Cameras Keyboard")
        # one write, one frame: 8 (no modifier: SimCamera1 forward), * (SHIFT+8: SimCamera2
        # forward), Esc 4 (ALT+4: SimCamera2 turns left); each keeps its own modifiers
        pane.keys("8*\x1b4", literal=True)
        wait_position(
            pane, "SimCamera1", ("\\+0.152", "\\+1.676", "\\+0.995", "\\+0.0", "\\+0.0", "\\+0.0")
        )
        moved = pane.wait_for(rf"^SimCamera2\s.*\n\s+{POSITION}")
        assert moved.groups() != camera2
        assert moved.group(4) == "-15.0" and moved.group(5) != "+10.0"  # turned once about y
        assert (
            position_of(pane, "SimHeadPos")[2] == "-0.005"
        )  # the head's keyboard no longer gets keys
        pane.keys("q", literal=True)
        pane.wait_for(r"EXIT=0")


def test_keys_of_one_frame_keep_their_own_modifiers_in_the_live_view():
    command = monitor(ALL_DEVICES, "Sim Head", "--no-mouse", "--rate", "5")
    with Pane(command, cols=160, rows=30) as pane:
        pane.wait_for(r"other keys and the mouse → Sim Keyboard")
        wait_position(
            pane, "Sim Head", ("\\+0.000", "\\+1.800", "\\+0.000", "\\+0.0", "\\+0.0", "\\+0.0")
        )
        pane.keys("Up", "Up", "S-Left")  # Up Up Shift+Left: forward twice, turn left once
        final = pane.wait_for(
            r"^Sim Head\s.*\n\s+position 0\s+x \+0\.000 y \+1\.800 z -0\.100 m"
            r"\s+rot\s+(\S+)\s+(\S+)\s+(\S+)°"
        )
        assert final.group(1) == "+0.0" and final.group(3) == "+0.0"
        assert float(final.group(2)) > 0  # one turn to the left, about y
        pane.keys("q", literal=True)
        pane.wait_for(r"EXIT=0")


def test_one_escape_cancels_the_marker_prompt():
    with Pane(monitor(ALL_DEVICES, "Sim Head", "--no-mouse"), cols=160, rows=30) as pane:
        pane.wait_for(r"other keys and the mouse → Sim Keyboard")
        pane.keys("m", literal=True)
        pane.wait_for(r"marker name \(Enter to write, Esc to cancel\)")
        pane.keys("Escape")
        pane.wait_for(r"^marker cancelled")
        pane.keys("q", literal=True)
        pane.wait_for(r"EXIT=0")


def test_keyboard_option_chooses_the_focus_and_an_unknown_name_is_a_usage_error():
    with Pane(
        monitor(SIM_BASE, SIM_WAND, "SimWandPos", "--keyboard", "Wand Keyboard", "--no-mouse"),
        cols=160,
        rows=30,
    ) as pane:
        pane.wait_for(r"other keys and the mouse → Wand Keyboard")
        pane.keys("q", literal=True)
        pane.wait_for(r"EXIT=0")
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "gadgetctl",
            "monitor",
            str(SIM_BASE),
            str(SIM_WAND),
            "--keyboard",
            "wand keybord",
            "--duration",
            "0",
            "--format",
            "table",
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 2
    assert "did you mean 'Wand Keyboard'" in done.stderr and "Traceback" not in done.stderr


def _keyboard() -> KeyboardMouseDevice:
    device = KeyboardMouseDevice()
    device.name = "Keys"
    return device


def test_each_press_of_a_frame_is_counted_with_the_modifiers_held_when_it_was_typed():
    device = _keyboard()

    def tap(key: Key, *mods: Key) -> list[KeyEvent]:
        return (
            [KeyEvent(m, True, 0.0) for m in mods]
            + [KeyEvent(key, True, 0.0), KeyEvent(key, False, 0.0)]
            + [KeyEvent(m, False, 0.0) for m in mods]
        )

    device.process_events(tap(Key.KEY_UP) + tap(Key.KEY_UP) + tap(Key.KEY_LEFT, Key.KEY_SHIFT))
    device.end_frame()
    assert device.key_pressed_with(Key.KEY_UP, Modifier.NONE) == 2
    assert device.key_pressed_with(Key.KEY_UP, Modifier.SHIFT) == 0
    assert device.key_pressed_with(Key.KEY_LEFT, Modifier.SHIFT) == 1
    assert device.key_pressed_with(Key.KEY_LEFT, Modifier.NONE) == 0
    assert device.key_pressed_with(Key.KEY_LEFT, Modifier.ANY) == 1
    device.process_events([KeyEvent(Key.KEY_CTRL, True, 0.0), KeyEvent(Key.KEY_A, True, 0.0)])
    device.end_frame()
    device.process_events([])
    device.end_frame()  # held over a frame: counted again with the modifier still held
    assert device.key_pressed_with(Key.KEY_A, Modifier.CTRL) == 1
    assert device.key_pressed_with(Key.KEY_A, Modifier.NONE) == 0
