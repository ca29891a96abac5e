"""The Fastrak plug-in as the command line sees it: unit ranges, emulate --list, doctor."""

from __future__ import annotations

import pytest

from gadgetctl.input.testing.commands import (
    emulated_and_serial_port_diagnosed,
    validate_reports_units_beyond,
)
from gadgetctl.input.testing.configs import configuration

pytestmark = pytest.mark.timeout(60)
CONFIG = configuration(
    "Fastrak_drv",
    """\
<fastrak name="F" version="2"><port>{port}</port></fastrak>
<position_proxy name="P3" version="1"><device>F</device><unit>3</unit></position_proxy>
<position_proxy name="P4" version="1"><device>F</device><unit>4</unit></position_proxy>
<digital_proxy name="B1" version="1"><device>F</device><unit>1</unit></digital_proxy>
""",
)


def test_units_beyond_four_stations_and_one_stylus_are_reported(tmp_path) -> None:
    validate_reports_units_beyond(
        CONFIG, tmp_path, ("'P4' reads position unit 4",), ("'B1' reads digital unit 1",)
    )


def test_emulate_lists_it_and_doctor_knows_its_serial_port(tmp_path) -> None:
    emulated_and_serial_port_diagnosed(CONFIG, tmp_path, "Fastrak_drv", ["fastrak"])
