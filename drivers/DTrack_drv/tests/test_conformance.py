"""DTrack_drv against bytes that do not come from our emulator (issue 23, "What to build" 1):
the ASCII output lines of A.R.T.'s own documentation, byte for byte.

Source of every fixture: A.R.T. GmbH, DTrack2 User Manual, "B Technical Appendix", "B.2
Output of Measurement Data via Ethernet" (reprinted in the ART Flystick2 and Flystick3 user
manuals, pages 259-265): the "Example" line of each identifier. The manual prints each long
example over several lines and says "(one line)"; they are joined with single spaces here,
and lines end in CR LF as DTrack sends them. Where a fixture departs from a printed example
(a count the manual defines but its example does not vary), the comment says so.
"""

from __future__ import annotations

import numpy as np
import pytest
from DTrack_drv.standalone import parse_frame

from gadgetctl.input import DeviceKind
from gadgetctl.input.testing import frames_until
from gadgetctl.input.testing.configs import free_udp_port, proxy
from gadgetctl.input.testing.fixtures import managers_fixture
from gadgetctl.input.testing.floods import send_datagrams

pytestmark = pytest.mark.timeout(30)

# B.2.1 Frame Counter, B.2.2 Timestamp
FRAME = "fr 21753"
TIMESTAMP = "ts 39596.024831"
# B.2.3 Standard 6DOF Bodies
BODY_6D = (
    "6d 1 [0 1.000][326.848 -187.216 109.503 -160.4704 -3.6963 -7.0913]"
    "[-0.940508 -0.339238 -0.019025 0.333599 -0.932599 0.137735 -0.064467 0.123194 0.990286]"
)
# B.2.4 Standard 6DOF Bodies (extended format); the manual's space between two blocks kept
BODY_6DI = (
    "6di 2 [0 1 2.135][326.848 -187.216 109.503][-0.940508 -0.339238 -0.019025 0.333599"
    " -0.932599 0.137735 -0.064467 0.123194 0.990286] [1 0 0.000][0.000 0.000 0.000]"
    "[0.000000 0.000000 0.000000 0.000000 0.000000 0.000000 0.000000 0.000000 0.000000]"
)
# B.2.6 Flysticks (old format)
FLYSTICK_6DF = (
    "6df 1 [0 1.000 2][261.103 116.520 41.085 19.6522 -57.3530 116.5992]"
    "[-0.241543 0.968868 -0.054332 -0.482366 -0.168461 -0.859619 -0.842010 -0.181427 0.508039]"
)
# B.2.7 Measurement Tools with sphere tip
TOOL_6DMT2 = (
    "6dmt2 1 1 [0 1.000 4 2.000][326.848 -187.216 109.503][0.911812 -0.038421 0.408806"
    " 0.095040 0.988324 -0.119094 -0.399457 0.147444 0.904817][0]"
    "[8.178e-04 9.166e-04 1.084e-03 4.463e-02 9.025e-03 1.286e-02]"
)
# B.2.8 Measurement Tool references (an identifier Gadgeteer does not read: ignored, not bad)
REFERENCE_6DMTR = (
    "6dmtr 1 1 [0 1.000][-485.245 -67.217 -38.328][0.681257 -0.315034 0.660790 -0.477531"
    " -0.875410 0.074967 0.554845 -0.366620 -0.746817]"
)
# B.2.9 Measurement Tools (old format)
TOOL_6DMT = (
    "6dmt 1 [0 1.000 0][326.848 -187.216 109.503][0.911812 -0.038421 0.408806 0.095040"
    " 0.988324 -0.119094 -0.399457 0.147444 0.904817]"
)

BODY_ROTATION = [-0.940508, -0.339238, -0.019025, 0.333599, -0.932599, 0.137735]
BODY_ROTATION += [-0.064467, 0.123194, 0.990286]


def datagram(*lines: str) -> bytes:
    return "".join(line + "\r\n" for line in lines).encode("ascii")


def column_major(values: list[float]) -> np.ndarray:
    """B.2.3: "Nine values b0 ... b8 form the rotation matrix R" column by column."""
    return np.array(values).reshape(3, 3).T


def test_the_frame_counter_timestamp_and_a_standard_body() -> None:
    frame = parse_frame(datagram(FRAME, TIMESTAMP, BODY_6D))
    assert frame is not None and frame.bad_lines == 0
    assert frame.frame == 21753 and frame.timestamp == 39596.024831
    (body,) = frame.bodies
    assert body.id == 0 and body.quality == 1.0 and body.tracked
    assert body.location_mm == (326.848, -187.216, 109.503)
    assert body.matrix[:3, 3] == pytest.approx([0.326848, -0.187216, 0.109503])
    assert body.matrix[:3, :3] == pytest.approx(column_major(BODY_ROTATION))


def test_the_extended_format_of_an_inertial_body_and_one_not_tracked() -> None:
    frame = parse_frame(datagram(FRAME, BODY_6DI))
    assert frame is not None and frame.bad_lines == 0
    tracked, lost = frame.bodies
    assert tracked.inertial and tracked.drift_error == 2.135 and tracked.tracked
    assert tracked.matrix[:3, :3] == pytest.approx(column_major(BODY_ROTATION))
    assert lost.id == 1 and not lost.tracked and lost.drift_error == 0.0


def test_an_old_format_flystick_with_its_second_button_pressed() -> None:
    frame = parse_frame(datagram(FRAME, FLYSTICK_6DF))
    assert frame is not None and frame.bad_lines == 0
    (stick,) = frame.flysticks
    assert stick.id == 0 and stick.tracked and stick.location_mm == (261.103, 116.520, 41.085)
    assert stick.buttons == (0, 1, 0, 0, 0, 0, 0, 0)  # bt 2: "switch 2 activated = bit 1 set"
    assert stick.joystick == (0.0, 0.0)
    rotation = [-0.241543, 0.968868, -0.054332, -0.482366, -0.168461, -0.859619]
    rotation += [-0.842010, -0.181427, 0.508039]
    assert stick.matrix[:3, :3] == pytest.approx(column_major(rotation))


def test_measurement_tools_in_both_formats_and_a_reference_that_is_ignored() -> None:
    frame = parse_frame(datagram(FRAME, TOOL_6DMT2, REFERENCE_6DMTR, TOOL_6DMT))
    assert frame is not None and frame.bad_lines == 0  # 6dmtr: an unknown tag, skipped
    sphere, old = frame.meatools
    assert sphere.tip_radius_mm == 2.0 and sphere.buttons == (0, 0, 0, 0)
    assert sphere.covariance == pytest.approx(
        (8.178e-04, 9.166e-04, 1.084e-03, 4.463e-02, 9.025e-03, 1.286e-02)
    )
    assert old.location_mm == sphere.location_mm == (326.848, -187.216, 109.503)
    assert old.matrix == pytest.approx(sphere.matrix)


def test_a_measurement_tool_line_counts_the_tools_that_follow_not_the_calibrated_ones() -> None:
    # Not a printed example: B.2.7 defines "The first number gives the number of calibrated
    # Measurement Tools. The second number gives the number [of] the following target data";
    # the example's "1 1" cannot tell them apart, so two are calibrated here and one follows.
    # (Fixed: the driver read the first number and rejected every such line.)
    line = TOOL_6DMT2.replace("6dmt2 1 1 ", "6dmt2 2 1 ")
    frame = parse_frame(datagram(FRAME, line))
    assert frame is not None and frame.bad_lines == 0 and len(frame.meatools) == 1


build = managers_fixture("DTrack_drv", name="build", ready=True)


def test_the_manuals_datagram_reaches_a_position_proxy(build) -> None:
    port = free_udp_port()
    element = f'<dtrack name="DT" version="1"><receive_port>{port}</receive_port></dtrack>\n'
    # units: the Flysticks first, then the tools, then the standard bodies (Gadgeteer's order)
    manager = build(element + proxy("position", "Body", "DT", 1))
    device = manager.device("DT")
    send_datagrams(port, [datagram(FRAME, TIMESTAMP, FLYSTICK_6DF, BODY_6D)])
    frames_until(manager, lambda: device.counters["decoded"] == 1)
    assert device.counters["bad_datagrams"] == 0 and device.counters["bad_lines"] == 0
    frames_until(manager, lambda: device.store.total(DeviceKind.POSITION) == 1)
    matrix = np.asarray(manager.device("DT").store.latest(DeviceKind.POSITION).values[1])
    assert matrix[:3, 3] == pytest.approx([0.326848, -0.187216, 0.109503])
    assert matrix[:3, :3] == pytest.approx(column_major(BODY_ROTATION))
