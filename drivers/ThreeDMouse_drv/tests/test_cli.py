"""The 3D mouse plug-in as the command line sees it: unit ranges, emulate --list, doctor."""

from __future__ import annotations

import json

import pytest

from gadgetctl.input.testing.commands import run_gadgetctl
from gadgetctl.input.testing.configs import configuration

pytestmark = pytest.mark.timeout(60)
CONFIG = configuration(
    "ThreeDMouse_drv",
    """\
<three_d_mouse name="F" version="1"><port>{port}</port></three_d_mouse>
<position_proxy name="P0" version="1"><device>F</device><unit>0</unit></position_proxy>
<position_proxy name="P1" version="1"><device>F</device><unit>1</unit></position_proxy>
<digital_proxy name="B2" version="1"><device>F</device><unit>2</unit></digital_proxy>
<digital_proxy name="B3" version="1"><device>F</device><unit>3</unit></digital_proxy>
""",
)


def test_units_beyond_one_pose_and_three_buttons_are_reported(tmp_path) -> None:
    path = tmp_path / "t.jconf"
    path.write_text(CONFIG.format(port="/dev/null"))
    out = run_gadgetctl("validate", str(path))
    problems = [line for line in out.stdout.splitlines() if "CFG034" in line]
    assert out.returncode == 1 and len(problems) == 2, out.stdout
    assert (
        "'P1' reads position unit 1" in problems[0] and "'B3' reads digital unit 3" in problems[1]
    )


def test_emulate_lists_it_and_doctor_knows_its_serial_port(tmp_path) -> None:
    listed = json.loads(run_gadgetctl("emulate", "--list", "--format", "json").stdout)["emulators"]
    assert next(e for e in listed if e["plugin"] == "ThreeDMouse_drv")["element_types"] == [
        "three_d_mouse"
    ]
    path = tmp_path / "t.jconf"
    path.write_text(CONFIG.format(port=tmp_path / "no-such-tty"))
    out = run_gadgetctl("doctor", str(path))
    problem = [line for line in out.stdout.splitlines() if "DRV100" in line]
    assert len(problem) == 1 and "no-such-tty does not exist" in problem[0], out.stdout
    assert "gadgetctl emulate ThreeDMouse_drv" in out.stdout
