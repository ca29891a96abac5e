"""The IS-900 plug-in as the command line sees it: unit ranges, emulate --list, doctor."""

from __future__ import annotations

import pytest

from gadgetctl.input.testing.commands import (
    emulated_and_serial_port_diagnosed,
    validate_reports_units_beyond,
)
from gadgetctl.input.testing.configs import configuration

pytestmark = pytest.mark.timeout(60)
CONFIG = configuration(
    "IS900_drv",
    """\
<intersense name="IS" version="1"><port>{port}</port><stations>
<intersense_station name="S" version="1"><digital_first>1</digital_first><digital_count>3</digital_count>
</intersense_station></stations></intersense>
<digital_proxy name="B3" version="1"><device>IS</device><unit>3</unit></digital_proxy>
<digital_proxy name="B4" version="1"><device>IS</device><unit>4</unit></digital_proxy>
<position_proxy name="P0" version="1"><device>IS</device><unit>0</unit></position_proxy>
<position_proxy name="P1" version="1"><device>IS</device><unit>1</unit></position_proxy>
""",
)


def test_units_beyond_the_stations_are_reported(tmp_path) -> None:
    validate_reports_units_beyond(
        CONFIG,
        tmp_path,
        ("'B4' reads digital unit 4", "units 0-3"),
        ("'P1' reads position unit 1", "(1 station)"),
    )


def test_emulate_lists_it_and_doctor_knows_its_serial_port(tmp_path) -> None:
    emulated_and_serial_port_diagnosed(CONFIG, tmp_path, "IS900_drv", ["intersense"])
