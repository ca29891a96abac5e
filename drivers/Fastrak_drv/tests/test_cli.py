"""The Fastrak plug-in as the command line sees it: unit ranges, emulate --list, doctor."""

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
    "Fastrak_drv",
    """\
<fastrak name="F" version="2"><port>{port}</port></fastrak>
<position_proxy name="P3" version="1"><device>F</device><unit>3</unit></position_proxy>
<position_proxy name="P4" version="1"><device>F</device><unit>4</unit></position_proxy>
<digital_proxy name="B1" version="1"><device>F</device><unit>1</unit></digital_proxy>
""",
)


def test_units_beyond_four_stations_and_one_stylus_are_reported(tmp_path) -> None:
    path = tmp_path / "t.jconf"
    path.write_text(CONFIG.format(port="/dev/null"))
    out = run_gadgetctl("validate", str(path))
    problems = reported(out, "CFG034")
    assert out.returncode == 1 and len(problems) == 2, out.stdout
    assert (
        "'P4' reads position unit 4" in problems[0] and "'B1' reads digital unit 1" in problems[1]
    )


def test_emulate_lists_it_and_doctor_knows_its_serial_port(tmp_path) -> None:
    assert emulated_types("Fastrak_drv") == ["fastrak"]
    path = tmp_path / "t.jconf"
    path.write_text(CONFIG.format(port=tmp_path / "no-such-tty"))
    doctor_finds_no_port(path, "Fastrak_drv", "no-such-tty")
