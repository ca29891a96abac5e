"""Simulated devices and the keyboard/mouse device, with the semantics of the reference's
section 9, driven by injected events."""

import math
from pathlib import Path

import numpy as np
import pytest

from gadgetctl.input import InputManager, Key, ManagerOptions
from gadgetctl.input.events import ScrollDirection
from gadgetctl.input.transforms import rotation_axis, translation
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.repository import default_repository

CORPUS_DEFINITIONS = Path("/work/shared/corpus/vrjuggler/modules/vrjuggler/data/definitions")
HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="test">\n<elements>\n'
)
KEYBOARD = (
    '<keyboard_mouse_device name="KB" version="2"><mouse_sensitivity>0.5</mouse_sensitivity>'
    "<scroll_as_buttons>true</scroll_as_buttons></keyboard_mouse_device>"
    '<keyboard_mouse_proxy name="KBP" version="1"><device>KB</device></keyboard_mouse_proxy>'
)
MOVE_KEYS = [
    "KEY_W",
    "KEY_S",
    "KEY_A",
    "KEY_D",
    "KEY_R",
    "KEY_F",
    "KEY_L",
    "KEY_J",
    "KEY_I",
    "KEY_K",
    "KEY_U",
    "KEY_O",
]


def key(code, modifier="ANY", name="k"):
    return (
        f'<key_modifier_pair name="{name}" version="1"><modifier_key>{modifier}</modifier_key>'
        f"<key>{code}</key></key_modifier_pair>"
    )


@pytest.fixture(scope="module")
def repo():
    return default_repository([CORPUS_DEFINITIONS] if CORPUS_DEFINITIONS.is_dir() else [])


@pytest.fixture
def make(repo, tmp_path):
    managers = []

    def build(body):
        path = tmp_path / f"test{len(managers)}.jconf"
        path.write_text(HEAD + body + "\n</elements>\n</configuration>\n")
        manager = InputManager(repo, ManagerOptions(retry_interval=None, entry_points=False))
        managers.append(manager)
        manager.configure(load_configuration([path]))
        return manager

    yield build
    for manager in managers:
        manager.shutdown()


def test_keyboard_counts_presses_holds_and_modifiers(make):
    m = make(KEYBOARD)
    kb = m.proxy("KBP")
    m.events.tap(Key.KEY_A)
    m.events.tap(Key.KEY_A)
    m.events.press(Key.KEY_B)
    m.update()
    assert kb.key_pressed(Key.KEY_A) == 2 and kb.key_pressed(Key.KEY_B) == 1
    m.update()
    assert kb.key_pressed(Key.KEY_A) == 0 and kb.key_pressed(Key.KEY_B) == 1  # still held
    m.events.release(Key.KEY_B)
    m.update()
    assert kb.key_pressed(Key.KEY_B) == 0
    assert kb.modifier_only(0)  # NONE: no modifier down
    m.events.press(Key.KEY_CTRL)
    m.update()
    assert kb.modifier_only(6) and not kb.modifier_only(5) and not kb.modifier_only(0)
    m.events.press(Key.KEY_SHIFT)
    m.update()
    assert not kb.modifier_only(6)  # two modifiers down: neither is the only one
    assert Key.KEY_SHIFT in kb.data


def test_mouse_motion_is_scaled_and_scroll_can_be_buttons(make):
    m = make(KEYBOARD)
    kb = m.proxy("KBP")
    m.events.move(10, -4)
    m.events.scroll(ScrollDirection.UP)
    m.update()
    assert kb.key_pressed(Key.MOUSE_POSX) == 5.0 and kb.key_pressed(Key.MOUSE_NEGY) == 2.0
    assert kb.key_pressed(Key.MOUSE_NEGX) == 0
    assert kb.key_pressed(Key.MOUSE_SCROLL_UP) == 1 and kb.key_pressed(Key.MOUSE_BUT4) == 1
    assert len(kb.samples()) == 2  # every event is kept as a sample


def test_input_window_routes_targeted_events(make):
    body = (
        KEYBOARD
        + """
    <keyboard_mouse_device name="Other" version="2"/>
    <keyboard_mouse_proxy name="Other Proxy" version="1"><device>Other</device></keyboard_mouse_proxy>
    <input_window name="Window" version="2"><keyboard_mouse_device_name>KB</keyboard_mouse_device_name></input_window>"""
    )
    m = make(body)
    assert not m.pending()
    m.events.press(Key.KEY_Q, target="Window")
    m.update()
    assert m.proxy("KBP").key_pressed(Key.KEY_Q) == 1
    assert m.proxy("Other Proxy").key_pressed(Key.KEY_Q) == 0


def test_simulated_analog_auto_return(make):
    body = (
        KEYBOARD
        + f"""
    <simulated_analog_device name="Spring" version="3">
      <keyboard_mouse_proxy>KBP</keyboard_mouse_proxy>
      <increment_keypress>{key("KEY_W")}</increment_keypress>
      <decrement_keypress>{key("KEY_S")}</decrement_keypress>
      <delta>4.0</delta><min>0.0</min><max>100.0</max><initial_value>50.0</initial_value>
      <auto_return>true</auto_return>
    </simulated_analog_device>
    <analog_proxy name="P" version="1"><device>Spring</device><unit>0</unit></analog_proxy>"""
    )
    m = make(body)
    proxy = m.proxy("P")
    for _ in range(3):
        m.events.tap(Key.KEY_W)
    m.update()
    assert proxy.raw == 62.0
    raws = []
    for _ in range(4):
        m.update()
        raws.append(proxy.raw)
    assert raws == [58.0, 54.0, 50.0, 50.0]  # one delta per frame, snapping to the initial value


def test_simulated_analog_with_fewer_decrement_keys_warns(make):
    body = (
        KEYBOARD
        + f"""
    <simulated_analog_device name="Two" version="3">
      <keyboard_mouse_proxy>KBP</keyboard_mouse_proxy>
      <increment_keypress>{key("KEY_W")}</increment_keypress>
      <increment_keypress>{key("KEY_E")}</increment_keypress>
      <decrement_keypress>{key("KEY_S")}</decrement_keypress>
    </simulated_analog_device>"""
    )
    m = make(body)
    assert any(d.code == "DRV023" for d in m.diagnostics)


def position_body(translation_system="Local", rotation_system="Local"):
    pairs = "".join(
        f"<key_pair>{key(k, 'NONE', f'm{i}')}</key_pair>" for i, k in enumerate(MOVE_KEYS)
    )
    return (
        KEYBOARD
        + f"""
    <simulated_positional_device name="Head" version="3">
      <keyboard_mouse_proxy>KBP</keyboard_mouse_proxy>{pairs}
      <initial_position>0.0</initial_position><initial_position>1.0</initial_position><initial_position>0.0</initial_position>
      <initial_rotation>0.0</initial_rotation><initial_rotation>90.0</initial_rotation><initial_rotation>0.0</initial_rotation>
      <translation_delta>0.5</translation_delta><rotation_delta>10.0</rotation_delta>
      <translation_coordinate_system>{translation_system}</translation_coordinate_system>
      <rotation_coordinate_system>{rotation_system}</rotation_coordinate_system>
    </simulated_positional_device>
    <position_proxy name="P" version="1"><device>Head</device><unit>0</unit></position_proxy>"""
    )


def start_matrix():
    return translation(0, 1, 0) @ rotation_axis((0, 1, 0), math.pi / 2)


def test_simulated_position_local_moves_follow_the_device_axes(make):
    m = make(position_body())
    m.events.tap(Key.KEY_W)  # forward: -Z of the device, which is turned 90° about Y
    m.events.tap(Key.KEY_W)
    m.update()
    expected = start_matrix() @ translation(0, 0, -1.0)
    np.testing.assert_allclose(m.proxy("P").matrix, expected, atol=1e-12)
    np.testing.assert_allclose(m.proxy("P").translation, [-1.0, 1.0, 0.0], atol=1e-12)
    m.events.tap(Key.KEY_J)  # yaw left: +10° about the device's Y
    m.update()
    expected = expected @ rotation_axis((0, 1, 0), math.radians(10))
    np.testing.assert_allclose(m.proxy("P").matrix, expected, atol=1e-12)


def test_simulated_position_global_moves_follow_the_world_axes(make):
    m = make(position_body("Global", "Global"))
    m.events.tap(Key.KEY_W)
    m.update()
    expected = translation(0, 0, -0.5) @ start_matrix()
    np.testing.assert_allclose(m.proxy("P").translation, [0.0, 1.0, -0.5], atol=1e-12)
    m.events.tap(Key.KEY_I)  # pitch up about the world X axis, in place
    m.update()
    turned = rotation_axis((1, 0, 0), math.radians(10)) @ expected
    turned[:3, 3] = expected[:3, 3]
    np.testing.assert_allclose(m.proxy("P").matrix, turned, atol=1e-12)


def test_simulated_position_roll_keys_turn_about_minus_z(make):
    m = make(position_body())
    m.events.tap(Key.KEY_U)  # roll counter-clockwise: about -Z
    m.update()
    expected = start_matrix() @ rotation_axis((0, 0, -1), math.radians(10))
    np.testing.assert_allclose(m.proxy("P").matrix, expected, atol=1e-12)


def test_simulated_position_with_missing_key_pairs_warns(make):
    body = (
        KEYBOARD
        + f"""
    <simulated_positional_device name="Half" version="3">
      <keyboard_mouse_proxy>KBP</keyboard_mouse_proxy><key_pair>{key("KEY_W")}</key_pair>
    </simulated_positional_device>"""
    )
    m = make(body)
    assert not m.pending()
    assert any(d.code == "DRV023" and "only 1 of 12" in d.message for d in m.diagnostics)


def test_relative_position_is_base_times_relative(make):
    body = (
        position_body()
        + """
    <simulated_setable_position name="Offset" version="1"/>
    <position_proxy name="Offset Proxy" version="1"><device>Offset</device><unit>0</unit></position_proxy>
    <simulated_relative_position name="Wand" version="1">
      <base_frame_proxy>P</base_frame_proxy><relative_proxy>Offset Proxy</relative_proxy>
    </simulated_relative_position>
    <position_proxy name="Wand Proxy" version="1"><device>Wand</device><unit>0</unit></position_proxy>"""
    )
    m = make(body)
    assert not m.pending()
    m.device("Offset").set_data([translation(0, 0, -0.4)])
    m.update()
    np.testing.assert_allclose(
        m.proxy("Wand Proxy").matrix, start_matrix() @ translation(0, 0, -0.4), atol=1e-12
    )


def test_simulated_devices_without_a_keyboard_proxy_stay_pending_with_a_reason(make):
    body = (
        KEYBOARD
        + """
    <simulated_digital_device name="Deaf" version="2"><keyboard_mouse_proxy></keyboard_mouse_proxy></simulated_digital_device>
    <simulated_digital_device name="Old" version="1"><event_window_proxy>Window Proxy</event_window_proxy></simulated_digital_device>
    <simulated_digital_device name="Lost" version="2"><keyboard_mouse_proxy>No Such Proxy</keyboard_mouse_proxy></simulated_digital_device>
    <keyboard_mouse_device name="Ancient" version="1"/>"""
    )
    m = make(body)
    reasons = {p.name: (p.code, p.message) for p in m.pending()}
    assert reasons["Deaf"][0] == "DRV032" and "keyboard_mouse_proxy is empty" in reasons["Deaf"][1]
    assert reasons["Old"][0] == "DRV037" and "event_window_proxy" in reasons["Old"][1]
    assert reasons["Lost"][0] == "DRV034" and "'No Such Proxy'" in reasons["Lost"][1]
    assert reasons["Ancient"][0] == "DRV037" and "version" in reasons["Ancient"][1]
