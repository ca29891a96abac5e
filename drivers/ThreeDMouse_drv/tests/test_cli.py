"""The 3D mouse plug-in as the command line sees it: unit ranges, emulate --list, doctor."""

from __future__ import annotations

import pytest

from gadgetctl.input.testing.commands import (
    emulated_and_serial_port_diagnosed,
    validate_reports_units_beyond,
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
    validate_reports_units_beyond(
        CONFIG, tmp_path, ("'P1' reads position unit 1",), ("'B3' reads digital unit 3",)
    )


def test_emulate_lists_it_and_doctor_knows_its_serial_port(tmp_path) -> None:
    emulated_and_serial_port_diagnosed(CONFIG, tmp_path, "ThreeDMouse_drv", ["three_d_mouse"])
