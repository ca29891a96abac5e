"""`gadgetctl view vrpn:Device@host`: a VRPN tracker with no configuration is drawn unit by
unit, against the VRPN driver's emulator (gadgetctl's VRPN server) on loopback."""

from __future__ import annotations

import json
import re
import sys

import numpy as np
import pytest

from conftest import REPO

sys.path.insert(0, str(REPO / "drivers"))
from VRPN_drv.emulator import VrpnEmulator, sensor_pose
from VRPN_drv.standalone import pose_matrix

pytestmark = pytest.mark.timeout(90)


def page_scene(page) -> dict:
    text = page.read_text(encoding="utf-8")
    match = re.search(r"<script>window\.gadgetctlScene=(.*?);window\.gadgetctlExport", text)
    assert match, "no scene state in the page"
    return json.loads(match.group(1))


def test_a_watched_vrpn_tracker_is_drawn_sensor_by_sensor(cli, tmp_path):
    page = tmp_path / "vrpn.html"
    with VrpnEmulator(0, scenario="idle", rate=100, sensors=3) as emu:
        result = cli("view", f"vrpn:Tracker0@{emu.address}", "--export", page, "--duration", "1")
    assert result.exit_code == 0, result.stderr
    scene = page_scene(page)
    tracker = f"Tracker0@{emu.address}"
    poses = {p["name"]: p for p in scene["poses"]}
    for unit in range(3):
        pose = poses[f"{tracker}[{unit}]"]
        assert pose["element"] == "device" and pose["state"] == "active"
        position, quat = sensor_pose(0, unit, False)
        assert np.allclose(pose["matrix"], pose_matrix(position, quat), atol=1e-6)
