"""The IS-900 plug-in as the command line sees it: unit ranges, emulate --list, doctor."""

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
    path = tmp_path / "t.jconf"
    path.write_text(CONFIG.format(port="/dev/null"))
    out = run_gadgetctl("validate", str(path))
    assert out.returncode == 1
    problems = reported(out, "CFG034")
    assert len(problems) == 2, out.stdout
    assert "'B4' reads digital unit 4" in problems[0] and "units 0-3" in problems[0]
    assert "'P1' reads position unit 1" in problems[1] and "(1 station)" in problems[1]


def test_emulate_lists_it_and_doctor_knows_its_serial_port(tmp_path) -> None:
    assert emulated_types("IS900_drv") == ["intersense"]
    path = tmp_path / "t.jconf"
    path.write_text(CONFIG.format(port=tmp_path / "no-such-tty"))
    doctor_finds_no_port(path, "IS900_drv", "no-such-tty")
