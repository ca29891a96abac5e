"""Proxies and aliases, driven frame by frame with injected key events: digital toggles,
analog normalisation and clamping, position filters against hand-computed matrices,
unit conversion, stupefied proxies."""

import math
from pathlib import Path

import numpy as np
import pytest

from gadgetctl.input import Digital, DigitalState, InputManager, Key, LengthUnit, ManagerOptions
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.registry import DeviceRegistry
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.repository import default_repository
from gadgetctl.jccl.searchpath import SearchPathEntry

CORPUS_DEFINITIONS = Path("/work/shared/corpus/vrjuggler/modules/vrjuggler/data/definitions")
PLUGINS = Path(__file__).parent / "data" / "plugins"
HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
    '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="test">\n<elements>\n'
)
KEYBOARD = (
    '<keyboard_mouse_device name="KB" version="2"/>'
    '<keyboard_mouse_proxy name="KBP" version="1"><device>KB</device></keyboard_mouse_proxy>'
)
ON, OFF, TOGGLE_ON, TOGGLE_OFF = (
    DigitalState.ON,
    DigitalState.OFF,
    DigitalState.TOGGLE_ON,
    DigitalState.TOGGLE_OFF,
)


def key(code, modifier="ANY", name="k"):
    return (
        f'<key_modifier_pair name="{name}" version="1"><modifier_key>{modifier}</modifier_key>'
        f"<key>{code}</key></key_modifier_pair>"
    )


@pytest.fixture(scope="module")
def repo():
    repo = default_repository([CORPUS_DEFINITIONS] if CORPUS_DEFINITIONS.is_dir() else [])
    directory = PLUGINS / "Button_drv"
    repo.load_entry(SearchPathEntry(raw=str(directory), path=directory, origin="test"))
    return repo


@pytest.fixture
def make(repo, tmp_path):
    managers = []

    def build(body, registry=None):
        path = tmp_path / f"test{len(managers)}.jconf"
        path.write_text(HEAD + body + "\n</elements>\n</configuration>\n")
        manager = InputManager(
            repo, ManagerOptions(retry_interval=None, entry_points=False), registry=registry
        )
        managers.append(manager)
        manager.configure(load_configuration([path]))
        return manager

    yield build
    for manager in managers:
        manager.shutdown()


# -- digital ------------------------------------------------------------------------------

BUTTONS = (
    KEYBOARD
    + f"""
<simulated_digital_device name="Buttons" version="2">
  <keyboard_mouse_proxy>KBP</keyboard_mouse_proxy>
  <key_pair>{key("KEY_A")}</key_pair>
  <key_pair>{key("KEY_B", "CTRL")}</key_pair>
</simulated_digital_device>
<digital_proxy name="A Proxy" version="1"><device>Buttons</device><unit>0</unit></digital_proxy>
<digital_proxy name="B Proxy" version="1"><device>Buttons</device><unit>1</unit></digital_proxy>
<alias name="VJButtonA" version="1"><proxy>A Proxy</proxy></alias>
"""
)


def frames(manager, name, count):
    result = []
    for _ in range(count):
        manager.update()
        result.append(manager.proxy(name).data)
    return result


def test_digital_press_hold_release(make):
    m = make(BUTTONS)
    assert not m.pending()
    assert frames(m, "VJButtonA", 1) == [OFF]
    m.events.press(Key.KEY_A)
    assert frames(m, "VJButtonA", 2) == [TOGGLE_ON, ON]
    m.events.release(Key.KEY_A)
    assert frames(m, "VJButtonA", 2) == [TOGGLE_OFF, OFF]


def test_digital_tap_inside_one_frame_is_not_lost(make):
    m = make(BUTTONS)
    m.update()
    m.events.tap(Key.KEY_A)  # pressed and released before the next frame
    assert frames(m, "A Proxy", 3) == [TOGGLE_ON, TOGGLE_OFF, OFF]


def test_digital_modifier_must_be_the_only_one_down(make):
    m = make(BUTTONS)
    m.events.tap(Key.KEY_B)
    assert frames(m, "B Proxy", 1) == [OFF]
    m.events.tap(Key.KEY_B, modifiers=[Key.KEY_SHIFT, Key.KEY_CTRL])
    assert frames(m, "B Proxy", 1) == [OFF]
    m.events.tap(Key.KEY_B, modifiers=[Key.KEY_CTRL])
    assert frames(m, "B Proxy", 2) == [TOGGLE_ON, TOGGLE_OFF]


class PushButtons(Digital):
    """A driver that reports every change, like a threaded driver between two frames."""

    ELEMENT_TYPE = "button_device"


def test_press_and_release_reported_by_a_device_within_one_frame(make):
    registry = DeviceRegistry.with_builtins()
    registry.register_device(PushButtons)
    m = make(
        '<button_device name="Pad" version="1"/>'
        '<digital_proxy name="P" version="1"><device>Pad</device><unit>0</unit></digital_proxy>',
        registry,
    )
    pad = m.device("Pad")
    m.update()
    pad.add_digital_sample([1])
    pad.add_digital_sample([0])
    assert frames(m, "P", 2) == [TOGGLE_ON, TOGGLE_OFF]
    pad.add_digital_sample([1])
    assert frames(m, "P", 2) == [TOGGLE_ON, ON]
    pad.add_digital_sample([0])
    pad.add_digital_sample([1])  # a release and a new press between two frames
    assert frames(m, "P", 2) == [TOGGLE_OFF, TOGGLE_ON]


# -- analog -------------------------------------------------------------------------------

ANALOG = (
    KEYBOARD
    + f"""
<simulated_analog_device name="Throttle" version="3">
  <keyboard_mouse_proxy>KBP</keyboard_mouse_proxy>
  <increment_keypress>{key("KEY_W")}</increment_keypress>
  <decrement_keypress>{key("KEY_S")}</decrement_keypress>
  <delta>100.0</delta><min>0.0</min><max>255.0</max><initial_value>0.0</initial_value>
</simulated_analog_device>
<analog_proxy name="T" version="1"><device>Throttle</device><unit>0</unit></analog_proxy>
"""
)


def test_analog_normalises_and_clamps(make):
    m = make(ANALOG)
    proxy = m.proxy("T")
    m.update()
    assert proxy.data == 0.0
    m.events.tap(Key.KEY_W)
    m.update()
    assert proxy.raw == 100.0
    assert proxy.data == pytest.approx(100.0 / 255.0)
    for _ in range(3):
        m.events.tap(Key.KEY_W)
    m.update()
    assert proxy.raw == 255.0 and proxy.data == 1.0  # clamped to max
    for _ in range(5):
        m.events.tap(Key.KEY_S)
    m.update()
    assert proxy.raw == 0.0 and proxy.data == 0.0  # clamped to min


def test_a_proxy_reads_its_device_when_read_and_a_digital_one_every_frame(make):
    m = make(
        ANALOG + '<analog_proxy name="Far" version="1"><device>Throttle</device><unit>3</unit>'
        "</analog_proxy>" + BUTTONS.replace(KEYBOARD, "")
    )
    reads: dict[str, int] = {}
    for name in ("T", "Far", "A Proxy"):
        proxy = m.proxy(name)
        real = proxy.update_data

        def counted(device, name=name, real=real):
            reads[name] = reads.get(name, 0) + 1
            real(device)

        proxy.update_data = counted
    analog = m.proxy("T")
    for _ in range(3):
        m.events.tap(Key.KEY_W)
        m.update()
    # nobody read the analog proxies: the frames did not; the digital one each frame
    assert reads == {"A Proxy": 3}
    assert analog.raw == 255.0 and analog.data == 1.0  # the newest, as every frame would
    assert analog.timestamp == m.device("Throttle").store.latest(DeviceKind.ANALOG).timestamp
    assert reads["T"] == 1
    assert analog.value == 1.0 and not analog.stupefied  # read again: nothing new to read
    assert reads["T"] == 1
    m.events.tap(Key.KEY_S)
    m.update()
    m.update()  # (a frame without samples: the newest stays)
    assert analog.raw == 155.0 and reads["T"] == 2
    far = m.proxy("Far")  # a unit out of range is found when the proxy is read
    assert far.stupefied and "unit 3 is out of range" in far.reason
    assert far.data == 0.0  # (the neutral value)
    assert "Far" not in reads  # (its state alone: no value was read for it)
    assert m.proxy("A Proxy").data == OFF


def test_analog_proxy_clamps_raw_values_outside_the_device_range(make):
    m = make(ANALOG)
    device = m.device("Throttle")
    device.analog_min, device.analog_max = 10.0, 20.0
    assert device.normalize(5.0) == 0.0
    assert device.normalize(25.0) == 1.0
    assert device.normalize(12.5) == pytest.approx(0.25)


def test_analog_min_equal_to_max_is_a_diagnostic_not_a_division_by_zero(make):
    m = make(ANALOG.replace("<max>255.0</max>", "<max>0.0</max>"))
    m.events.tap(Key.KEY_W)
    m.update()
    assert m.proxy("T").data == 0.0
    codes = [d for d in m.diagnostics if d.code == "DRV020"]
    assert codes and "empty" in codes[0].message and codes[0].line is not None


# -- position -----------------------------------------------------------------------------

SETABLE = """
<simulated_setable_position name="Tracker" version="1">
  <position_filters>
    <position_transform_filter name="Device Filter" version="1">
      <pre_translate>1.0</pre_translate><pre_translate>2.0</pre_translate><pre_translate>3.0</pre_translate>
      <pre_rotation>0.0</pre_rotation><pre_rotation>90.0</pre_rotation><pre_rotation>0.0</pre_rotation>
      <custom_scale>1.0</custom_scale><device_units>Inches</device_units>
      <post_translate>10.0</post_translate><post_translate>0.0</post_translate><post_translate>0.0</post_translate>
      <post_rotation>0.0</post_rotation><post_rotation>0.0</post_rotation><post_rotation>0.0</post_rotation>
    </position_transform_filter>
  </position_filters>
</simulated_setable_position>
<position_proxy name="Raw" version="1"><device>Tracker</device><unit>0</unit></position_proxy>
<position_proxy name="Lowered" version="1">
  <device>Tracker</device><unit>0</unit>
  <position_filters>
    <full_position_transform_filter name="Proxy Filter" version="1">
      <pre_xform>1</pre_xform><pre_xform>0</pre_xform><pre_xform>0</pre_xform><pre_xform>0</pre_xform>
      <pre_xform>0</pre_xform><pre_xform>1</pre_xform><pre_xform>0</pre_xform><pre_xform>0</pre_xform>
      <pre_xform>0</pre_xform><pre_xform>0</pre_xform><pre_xform>1</pre_xform><pre_xform>-1</pre_xform>
      <pre_xform>0</pre_xform><pre_xform>0</pre_xform><pre_xform>0</pre_xform><pre_xform>1</pre_xform>
    </full_position_transform_filter>
  </position_filters>
</position_proxy>
"""


def test_position_filters_at_device_and_proxy_level(make):
    m = make(SETABLE)
    sensor = np.eye(4)
    sensor[0, 3] = 100.0  # 100 inches along x
    m.device("Tracker").set_data([sensor])
    m.update()
    # device filter: Pre · S(M · Post) with Post = T(10 in, 0, 0), S = inches -> meters,
    # Pre = T(1, 2, 3) · Ry(90°); Ry(90°) turns +x into -z: 110 in = 2.794 m -> (0, 0, -2.794)
    expected = np.array(
        [
            [0.0, 0.0, 1.0, 1.0],
            [0.0, 1.0, 0.0, 2.0],
            [-1.0, 0.0, 0.0, 3.0 - 2.794],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )
    np.testing.assert_allclose(m.proxy("Raw").matrix, expected, atol=1e-12)
    # proxy filter: Pre · M · Post with Pre = T(0, 0, -1) (row-major values), Post = identity
    lowered = expected.copy()
    lowered[2, 3] -= 1.0
    np.testing.assert_allclose(m.proxy("Lowered").matrix, lowered, atol=1e-12)


def test_proxies_give_meters_and_convert_on_request(make):
    m = make(SETABLE)
    m.device("Tracker").set_data([np.eye(4)])
    m.update()
    proxy = m.proxy("Raw")
    assert proxy.matrix.dtype == np.float64
    feet = proxy.matrix_in(LengthUnit.FEET)
    np.testing.assert_allclose(feet[:3, 3], proxy.translation / 0.3048)
    np.testing.assert_allclose(feet[:3, :3], proxy.matrix[:3, :3])  # rotation kept
    np.testing.assert_allclose(
        proxy.matrix_in(LengthUnit.CENTIMETERS)[:3, 3], proxy.translation * 100
    )


def test_device_filters_apply_once_on_simulated_positions(make):
    body = (
        KEYBOARD
        + """
    <simulated_positional_device name="Head" version="3">
      <keyboard_mouse_proxy>KBP</keyboard_mouse_proxy>
      <initial_position>0.0</initial_position><initial_position>1.0</initial_position><initial_position>0.0</initial_position>
      <position_filters>
        <position_transform_filter name="Up" version="1">
          <pre_translate>0.0</pre_translate><pre_translate>0.5</pre_translate><pre_translate>0.0</pre_translate>
        </position_transform_filter>
      </position_filters>
    </simulated_positional_device>
    <position_proxy name="HP" version="1"><device>Head</device><unit>0</unit></position_proxy>"""
    )
    m = make(body)
    m.update()
    np.testing.assert_allclose(m.proxy("HP").translation, [0.0, 1.5, 0.0])  # once, not twice


# -- stupefied proxies --------------------------------------------------------------------


def test_stupefied_proxies_return_neutral_values_and_say_why(make):
    body = (
        BUTTONS
        + """
    <digital_proxy name="Ghost" version="1"><device>Nobody</device><unit>0</unit></digital_proxy>
    <position_proxy name="Wrong Type" version="1"><device>Buttons</device><unit>0</unit></position_proxy>
    <digital_proxy name="Far Unit" version="1"><device>Buttons</device><unit>7</unit></digital_proxy>
    <analog_proxy name="Empty" version="1"><device></device></analog_proxy>"""
    )
    m = make(body)
    m.events.press(Key.KEY_A)
    m.update()
    assert m.proxy("Ghost").stupefied and m.proxy("Ghost").data == OFF
    assert "'Nobody' is not configured" in m.proxy("Ghost").reason
    wrong = m.proxy("Wrong Type")
    assert wrong.stupefied and "provides no position data" in wrong.reason
    np.testing.assert_array_equal(wrong.matrix, np.eye(4))
    far = m.proxy("Far Unit")
    assert far.stupefied and far.data == OFF and "unit 7 is out of range" in far.reason
    assert m.proxy("Empty").stupefied and m.proxy("Empty").data == 0.0
    assert not m.pending()  # stupefied proxies are configured, not pending
    states = {s.name: s.state for s in m.statuses()}
    assert states["Ghost"] == "stupefied" and states["A Proxy"] == "active"


def test_aliases_resolve_to_proxies_and_any_name_can_be_looked_up(make):
    m = make(BUTTONS)
    assert m.proxy("VJButtonA") is m.proxy("A Proxy")
    assert m.lookup("VJButtonA") is m.proxy("A Proxy")
    assert m.lookup("Buttons") is m.device("Buttons")
    assert m.lookup("KB") is m.device("KB")
    assert m.lookup("nothing") is None
    assert m.aliases["VJButtonA"] == "A Proxy"


# -- glove, gesture, command, string, hat -------------------------------------------------

GLOVES = (
    KEYBOARD
    + f"""
<simulated_positional_device name="Hand" version="3"><keyboard_mouse_proxy>KBP</keyboard_mouse_proxy></simulated_positional_device>
<position_proxy name="Hand Proxy" version="1"><device>Hand</device><unit>0</unit></position_proxy>
<simulated_digital_glove name="Glove" version="3">
  <keyboard_mouse_proxy>KBP</keyboard_mouse_proxy>
  {"".join(f"<key_pair>{key(f'KEY_{n}')}</key_pair>" for n in "1234567890")}
  <left_glove_position>Hand Proxy</left_glove_position>
  <right_glove_position>Hand Proxy</right_glove_position>
</simulated_digital_glove>
<glove_proxy name="Left" version="1"><device>Glove</device><unit>0</unit></glove_proxy>
<glove_proxy name="Right" version="1"><device>Glove</device><unit>1</unit></glove_proxy>
<digital_proxy name="Right Index" version="1"><device>Glove</device><unit>6</unit></digital_proxy>
<simulated_glove_gesture name="Gestures" version="3">
  <keyboard_mouse_proxy>KBP</keyboard_mouse_proxy>
  <key_presses>{key("KEY_F1", name="open")}</key_presses>
  <key_presses>{key("KEY_F2", name="fist")}</key_presses>
  <glove_position>Hand Proxy</glove_position>
</simulated_glove_gesture>
<gesture_proxy name="Gesture" version="1"><device>Gestures</device></gesture_proxy>
"""
)


def test_glove_fingers_and_gestures(make):
    m = make(GLOVES)
    assert not m.pending(), [p.message for p in m.pending()]
    m.events.press(Key.KEY_2)  # left index
    m.events.press(Key.KEY_7)  # right index
    m.events.tap(Key.KEY_F2)
    m.update()
    left, right = m.proxy("Left").data, m.proxy("Right").data
    assert np.all(left[1] == math.pi / 2) and np.all(left[0] == 0.0)
    assert np.all(right[1] == math.pi / 2) and right.sum() == pytest.approx(2 * math.pi)
    assert m.proxy("Right Index").data == TOGGLE_ON
    np.testing.assert_allclose(m.proxy("Left").position, m.proxy("Hand Proxy").matrix)
    gesture = m.proxy("Gesture")
    assert gesture.data == 1 and gesture.gesture_name == "fist"
    m.update()
    assert gesture.data == 1  # a gesture stays until another key is pressed


@pytest.mark.timeout(20)
def test_command_string_and_hat_proxies_update(make):
    body = """
    <waveform_device name="Events" version="1"><rate>200.0</rate><event_period>0.02</event_period></waveform_device>
    <command_proxy name="C" version="1"><device>Events</device><unit>0</unit></command_proxy>
    <string_proxy name="S" version="1"><device>Events</device><unit>0</unit></string_proxy>
    <hat_proxy name="H" version="1"><device>Events</device><unit>0</unit></hat_proxy>"""
    m = make(body)
    seen_strings, seen_hats = set(), set()
    for _ in range(400):
        m.update()
        seen_strings.add(m.proxy("S").data)
        seen_hats.add(int(m.proxy("H").data))
        if m.proxy("C").data >= 3 and len(seen_hats) >= 3:
            break
        __import__("time").sleep(0.005)
    assert m.proxy("C").data >= 3
    assert f"event {m.proxy('C').data}" == m.proxy("S").data  # the string proxy does update
    assert any(s.startswith("event ") for s in seen_strings)
    assert len(seen_hats) >= 3


def test_a_device_warning_points_at_its_own_element_found_when_made(make):
    """Issue 27: a device found its element's column (a scan of the line) when configured,
    for a warning few devices ever make (10,000 waveform devices: 2 MB and 0.1 s); it is
    found when a warning is made, and still tells two elements on one line apart."""
    first = '<waveform_device name="A" version="1"><min>1.0</min><max>0.0</max></waveform_device>'
    second = '<waveform_device name="B" version="1"><min>2.0</min><max>2.0</max></waveform_device>'
    m = make(first + " " + second)
    found = {
        d.message.split(":")[0]: (d.line, d.column) for d in m.diagnostics if d.code == "DRV020"
    }
    assert found == {"A": (5, 1), "B": (5, len(first) + 2)}
