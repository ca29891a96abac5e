"""The IS-900 plug-in as the command line sees it: unit ranges, emulate --list, doctor."""

from __future__ import annotations

import json

import pytest

from gadgetctl.input.testing.commands import run_gadgetctl
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
    problems = [line for line in out.stdout.splitlines() if "CFG034" in line]
    assert len(problems) == 2, out.stdout
    assert "'B4' reads digital unit 4" in problems[0] and "units 0-3" in problems[0]
    assert "'P1' reads position unit 1" in problems[1] and "(1 station)" in problems[1]


def test_emulate_lists_it_and_doctor_knows_its_serial_port(tmp_path) -> None:
    listed = json.loads(run_gadgetctl("emulate", "--list", "--format", "json").stdout)["emulators"]
    entry = next(e for e in listed if e["plugin"] == "IS900_drv")
    assert entry["element_types"] == ["intersense"]
    path = tmp_path / "t.jconf"
    path.write_text(CONFIG.format(port=tmp_path / "no-such-tty"))
    out = run_gadgetctl("doctor", str(path))
    port_problem = [line for line in out.stdout.splitlines() if "DRV100" in line]
    assert len(port_problem) == 1 and "no-such-tty does not exist" in port_problem[0], out.stdout
    assert "gadgetctl emulate IS900_drv" in out.stdout
