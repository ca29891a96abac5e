"""The scene model of `gadgetctl view` (no browser): layout, geometry through position
filters, states, and the command without viser."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.manager import InputManager
from gadgetctl.input.testing.configs import CONFIGURATION_HEAD, CONFIGURATION_TAIL, corpus_file
from gadgetctl.monitor.session import MonitorSession
from gadgetctl.view.layout import read_layout
from gadgetctl.view.scene import SceneModel

pytestmark = pytest.mark.timeout(60)

FEET = 0.3048
PRE_T, PRE_R = (0.5, 1.0, -0.25), (0.0, 90.0, 0.0)
POST_T, POST_R = (0.2, 0.0, 0.1), (30.0, 0.0, 0.0)  # post_translate is in device units (feet)
CENTRE, RADIUS = (1.0, 4.0, 2.0), 1.5  # feet, as the tracker reports them

FILTERED = f"""
<waveform_device name="Tracker" version="1">
  <rate>120.0</rate>
  <position_path>circle</position_path>
  <position_period>3.0</position_period>
  <position_radius>{RADIUS}</position_radius>
  <position_center>{CENTRE[0]}</position_center>
  <position_center>{CENTRE[1]}</position_center>
  <position_center>{CENTRE[2]}</position_center>
  <event_period>0.0</event_period>
</waveform_device>
<position_proxy name="Head" version="1">
  <device>Tracker</device>
  <unit>0</unit>
  <position_filters>
    <position_transform_filter name="Feet to the world" version="1">
      {"".join(f"<pre_translate>{v}</pre_translate>" for v in PRE_T)}
      {"".join(f"<pre_rotation>{v}</pre_rotation>" for v in PRE_R)}
      <custom_scale>1.0</custom_scale>
      <device_units>Feet</device_units>
      {"".join(f"<post_translate>{v}</post_translate>" for v in POST_T)}
      {"".join(f"<post_rotation>{v}</post_rotation>" for v in POST_R)}
    </position_transform_filter>
  </position_filters>
</position_proxy>
<alias name="VJHead" version="1"><proxy>Head</proxy></alias>
<user name="User1" version="1"><head_position>VJHead</head_position><interocular_distance>0.065</interocular_distance></user>
<position_proxy name="Nowhere" version="1"><device>No such tracker</device><unit>0</unit></position_proxy>
"""


def write(tmp_path, body: str):
    path = tmp_path / "view.jconf"
    path.write_text(
        CONFIGURATION_HEAD.format(name="view", driver="none") + body + CONFIGURATION_TAIL,
        encoding="utf-8",
    )
    return path


def rotation(x: float, y: float, z: float) -> np.ndarray:
    """Rx(x) Ry(y) Rz(z) in degrees, written out here (not gadgetctl's)."""
    a, b, c = np.radians((x, y, z))
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rz = np.array([[np.cos(c), -np.sin(c), 0], [np.sin(c), np.cos(c), 0], [0, 0, 1]])
    m = np.eye(4)
    m[:3, :3] = rx @ ry @ rz
    return m


def moved(t, r) -> np.ndarray:
    m = rotation(*r)
    m[:3, 3] = t
    return m


@pytest.fixture
def running(tmp_path):
    made = []

    def start(body: str, selectors=()):
        manager, configuration = InputManager.from_files([write(tmp_path, body)])
        session = MonitorSession(manager, configuration, selectors=list(selectors), rate=60)
        session.start()
        made.append(manager)
        return session, SceneModel(session, read_layout(configuration.elements, manager.repo))

    yield start
    for manager in made:
        manager.shutdown()


def run_until(session, model, check, frames=600):
    for _ in session.frames(frames=frames):
        model.update()
        if check():
            return
    raise AssertionError("the condition never held")


def test_a_filtered_pose_is_where_the_proxy_puts_it_and_its_raw_frame_where_the_inverse_does(
    running,
):
    session, model = running(FILTERED)
    proxy = session.manager.proxy("Head")
    run_until(session, model, lambda: model.poses["Head"].matrix is not None)
    for _ in session.frames(frames=5):
        model.update()
    snapshot = model.snapshot()
    head = next(p for p in snapshot["poses"] if p["name"] == "Head")
    world = np.array(head["matrix"])
    assert np.allclose(world, proxy.matrix, atol=1e-5)  # what the proxy delivers
    alias = next(p for p in snapshot["poses"] if p["name"] == "VJHead")
    assert np.allclose(alias["matrix"], proxy.matrix, atol=1e-5)
    # The filter: W = Pre . D . M . Post . D^-1 (D scales translations by device_units), so
    # the raw sample is M = D^-1 . Pre^-1 . W . D . Post^-1.
    d = np.diag((FEET, FEET, FEET, 1.0))
    raw = (
        np.linalg.inv(d)
        @ np.linalg.inv(moved(PRE_T, PRE_R))
        @ proxy.matrix
        @ d
        @ np.linalg.inv(moved(POST_T, POST_R))
    )
    assert np.allclose(head["raw"], raw, atol=1e-5)
    # ... which is a point of the tracker's own circle, in feet
    x, y, z = raw[:3, 3]
    assert y == pytest.approx(CENTRE[1], abs=1e-4)
    assert np.hypot(x - CENTRE[0], z - CENTRE[2]) == pytest.approx(RADIUS, abs=1e-4)
    # the tracker's frame sits where pre_translate and pre_rotation put it
    tracker = np.array(head["tracker_frame"])
    assert np.allclose(tracker, moved(PRE_T, PRE_R), atol=1e-5)
    # the user's eyes straddle the head along its X axis
    user = snapshot["users"][0]
    assert np.allclose(user["position"], proxy.matrix[:3, 3], atol=1e-5)
    assert np.linalg.norm(np.subtract(user["right_eye"], user["left_eye"])) == pytest.approx(0.065)
    assert np.allclose(user["sight"], -proxy.matrix[:3, 2], atol=1e-5)


def test_a_stupefied_proxy_is_shown_with_its_reason(running):
    session, model = running(FILTERED, ["Nowhere", "Head"])
    run_until(session, model, lambda: bool(model.elements))
    nowhere = next(p for p in model.snapshot()["poses"] if p["name"] == "Nowhere")
    assert nowhere["state"] == "stupefied"
    assert "No such tracker" in nowhere["reason"]
    assert nowhere["matrix"] is None  # never had a pose: listed, not drawn


def test_the_c4_layout_has_its_four_screens_and_user():
    manager, configuration = InputManager.from_files(
        [corpus_file("C4.base.jconf"), corpus_file("C4.displays.closed.jconf")]
    )
    layout = read_layout(configuration.elements, manager.repo)
    names = {s.name: s for s in layout.surfaces}
    assert set(names) == {f"{w}Screen viewport" for w in ("Right", "Left", "Front", "Floor")}
    front = names["FrontScreen viewport"]
    assert front.corners[0] == (-1.8288, 0.0, -1.8288)  # lower left
    assert front.corners[2] == (1.8288, 2.7432, -1.8288)  # upper right
    assert [(u.name, u.head, u.interocular) for u in layout.users] == [("User1", "VJHead", 0.069)]


def test_without_viser_view_names_the_extra_to_install(tmp_path):
    config = write(tmp_path, FILTERED)
    code = (
        "import sys; sys.modules['viser'] = None\n"
        "from gadgetctl.cli.main import run\n"
        f"sys.argv = ['gadgetctl', 'view', {str(config)!r}, '--no-check']\n"
        "run()\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert "gadgetctl[view]" in lines[0] and "viser" in lines[0]


TRACKED = """
<waveform_device name="Board Tracker" version="1">
  <rate>120.0</rate>
  <position_path>spin</position_path>
  <position_period>4.0</position_period>
  <position_center>0.5</position_center>
  <position_center>1.0</position_center>
  <position_center>-1.0</position_center>
  <event_period>0.0</event_period>
</waveform_device>
<position_proxy name="Board" version="1"><device>Board Tracker</device><unit>0</unit></position_proxy>
<display_window name="Tablet" version="6">
  <surface_viewports>
    <surface_viewport name="Tablet viewport" version="2">
      <lower_left_corner>-0.2</lower_left_corner><lower_left_corner>-0.1</lower_left_corner><lower_left_corner>0</lower_left_corner>
      <lower_right_corner>0.2</lower_right_corner><lower_right_corner>-0.1</lower_right_corner><lower_right_corner>0</lower_right_corner>
      <upper_right_corner>0.2</upper_right_corner><upper_right_corner>0.1</upper_right_corner><upper_right_corner>0</upper_right_corner>
      <upper_left_corner>-0.2</upper_left_corner><upper_left_corner>0.1</upper_left_corner><upper_left_corner>0</upper_left_corner>
      <tracked>true</tracked>
      <tracker_proxy>Board</tracker_proxy>
    </surface_viewport>
  </surface_viewports>
</display_window>
<waveform_device name="Sticks" version="1">
  <rate>120.0</rate>
  <analog_waveform>sine</analog_waveform>
  <analog_waveform>triangle</analog_waveform>
  <min>-1.0</min>
  <max>1.0</max>
  <button_period>0.5</button_period>
  <event_period>0.0</event_period>
</waveform_device>
"""


def test_a_tracked_surface_follows_its_tracker_proxy_and_units_are_listed(running):
    session, model = running(TRACKED)
    proxy = session.manager.proxy("Board")
    run_until(
        session,
        model,
        lambda: (
            model.poses["Board"].matrix is not None
            and abs(model.poses["Board"].matrix[0, 2]) > 0.1  # turned away from the start
            and "Sticks" in model.units
        ),
    )
    surface = model.snapshot()["surfaces"][0]
    assert surface["tracked"] and surface["tracker_proxy"] == "Board"
    local = np.array([[-0.2, -0.1, 0, 1], [0.2, -0.1, 0, 1], [0.2, 0.1, 0, 1], [-0.2, 0.1, 0, 1]])
    expected = (proxy.matrix @ local.T).T[:, :3]
    assert np.allclose(surface["corners"], expected, atol=1e-5)
    sticks = next(u for u in model.snapshot()["units"] if u["name"] == "Sticks")
    assert len(sticks["analog"]) == 2 and all(0.0 <= v <= 1.0 for v in sticks["analog"])
    device = session.manager.device("Sticks")
    assert len(sticks["digital"]) == len(device.store.latest(DeviceKind.DIGITAL).values)


def test_a_simulator_camera_sits_on_its_proxy():
    manager, configuration = InputManager.from_files([corpus_file("sim.base.jconf")])
    try:
        session = MonitorSession(manager, configuration, rate=60)
        session.start()
        model = SceneModel(session, read_layout(configuration.elements, manager.repo))
        run_until(session, model, lambda: model.poses["SimCam1 Proxy"].matrix is not None)
        camera = model.snapshot()["cameras"][0]
        assert camera["proxy"] == "SimCam1 Proxy" and camera["vertical_fov"] > 0
        assert np.allclose(camera["matrix"], manager.proxy("SimCam1 Proxy").matrix, atol=1e-6)
    finally:
        manager.shutdown()
