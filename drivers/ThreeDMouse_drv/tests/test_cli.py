"""The 3D mouse plug-in as the command line sees it: unit ranges, emulate --list, doctor."""

from __future__ import annotations

import pytest

from gadgetctl.input.testing.commands import (
    doctor_finds_no_port,
    emulated_types,
    reported,
    run_gadgetctl,
)
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
    problems = reported(out, "CFG034")
    assert out.returncode == 1 and len(problems) == 2, out.stdout
    assert (
        "'P1' reads position unit 1" in problems[0] and "'B3' reads digital unit 3" in problems[1]
    )


def test_emulate_lists_it_and_doctor_knows_its_serial_port(tmp_path) -> None:
    assert emulated_types("ThreeDMouse_drv") == ["three_d_mouse"]
    path = tmp_path / "t.jconf"
    path.write_text(CONFIG.format(port=tmp_path / "no-such-tty"))
    doctor_finds_no_port(path, "ThreeDMouse_drv", "no-such-tty")
