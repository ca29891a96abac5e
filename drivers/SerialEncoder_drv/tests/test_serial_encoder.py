"""The US Digital serial encoder driver against its emulator over a real pty pair, standalone
and in an input manager."""

from __future__ import annotations

import math
import struct
from collections.abc import Callable

import numpy as np
import pytest
from SerialEncoder_drv.emulator import PRESETS, SerialEncoderEmulator
from SerialEncoder_drv.standalone import MAX_POSITION, SerialEncoderBus, decode_reply, table_matrix

from gadgetctl.input import InputManager
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.testing import faults_then_resumes, wait_until
from gadgetctl.input.testing.fixtures import emulator_fixture, managers_fixture

pytestmark = pytest.mark.timeout(30)

# reply_timeout is a hang guard: under load a late answer would count as a timeout and shift the
# pairing of answers the tests compare, so it is generous (answers normally take milliseconds)
FAST = {"poll_rate": 400.0, "reply_timeout": 3.0, "poll_interval": 0.005}


def encoders(name: str, port: str, baud: str = "<baud>9600</baud>") -> str:
    return (
        f'<serial_encoder name="{name}" version="1"><port>{port}</port>{baud}</serial_encoder>\n'
        f'<position_proxy name="{name} Proxy" version="1"><device>{name}</device><unit>0</unit></position_proxy>\n'
    )


def expected_matrix(tilt: float, height: float) -> np.ndarray:
    """From the protocol description: rotate about X by the tilt, then lift by the height."""
    a = math.radians(tilt)
    rot = np.array(
        [
            [1, 0, 0, 0],
            [0, math.cos(a), -math.sin(a), 0],
            [0, math.sin(a), math.cos(a), 0],
            [0, 0, 0, 1],
        ]
    )
    lift = np.eye(4)
    lift[1, 3] = height / 39.37  # Gadgeteer counts 39.37 inches to the meter
    return lift @ rot


emulator = emulator_fixture(SerialEncoderEmulator, rate=2000.0)
managers = managers_fixture("SerialEncoder_drv", tune={"serial_encoder": FAST})


def collect(manager: InputManager, name: str) -> tuple[Callable[[], None], list]:
    device = manager.device(name)
    matrices: list[np.ndarray] = []

    def frame() -> None:
        manager.update()
        matrices.extend(np.asarray(s.values)[0] for s in device.store.frame(DeviceKind.POSITION))

    return frame, matrices


def pairs(sent: list[tuple[int, float]]) -> list[tuple[float, float]]:
    """(tilt, height) of every poll whose two answers were both good."""
    out, tilt = [], None
    for address, value in sent:
        if address == 1:
            tilt = value
        elif tilt is not None:
            out.append((tilt, value))
            tilt = None
    return out


# -- the wire format -----------------------------------------------------------------------------


def test_replies_decode_as_the_protocol_says() -> None:
    assert decode_reply(2, bytes([0x12]) + struct.pack(">f", 36.5)) == 36.5
    assert decode_reply(1, bytes([0x11, 0xC1, 0xA0, 0, 0])) == -20.0  # big-endian float
    assert decode_reply(1, bytes([0x12]) + struct.pack(">f", 1.0)) is None  # another encoder's
    assert decode_reply(1, bytes([0x11, 0x7F, 0xC0, 0, 0])) is None  # NaN
    assert decode_reply(1, bytes([0x11]) + struct.pack(">f", MAX_POSITION * 2)) is None
    np.testing.assert_allclose(table_matrix(90.0, 39.37), expected_matrix(90.0, 39.37), atol=1e-12)
    np.testing.assert_allclose(table_matrix(0.0, 39.37)[1, 3], 1.0)  # 39.37 in is a meter


# -- standalone over the pty ------------------------------------------------------------------


def test_standalone_reads_both_encoders(emulator) -> None:
    emu = emulator("buttons")
    with SerialEncoderBus(emu.address, reply_timeout=3.0) as bus:
        readings = [bus.table() for _ in range(12)]
        bus.reply_timeout = 0.3
        assert bus.position(7) is None  # nobody at address 7: a timeout, not a fault
        assert bus.counters.timeouts == 1
    assert emu.commands[:4] == [0x11, 0x12, 0x11, 0x12]
    assert readings == pairs(emu.sent)[:12]
    assert set(readings) <= set(PRESETS) and len(set(readings)) >= 2


# -- in the input manager ---------------------------------------------------------------------


def test_table_matrix_reaches_the_proxy(emulator, managers) -> None:
    emu = emulator("motion")
    manager = managers(encoders("Table", emu.address))
    assert not manager.pending()  # the C++ config() failed exactly when the bus was fine
    frame, matrices = collect(manager, "Table")
    assert wait_until(lambda: len(matrices) > 20, step=frame)
    want = pairs(emu.sent)[: len(matrices)]
    for got, (tilt, height) in zip(matrices, want, strict=True):
        np.testing.assert_allclose(got, expected_matrix(tilt, height), atol=1e-6)
    assert any(abs(t) > 5 for t, _ in want)  # it really tilted
    proxy = manager.proxy("Table Proxy").data
    np.testing.assert_allclose(proxy, matrices[-1], atol=1e-6)


def test_garbage_is_resynchronised_and_counted_without_a_fault(emulator, managers) -> None:
    emu = emulator("garbage")
    manager = managers(encoders("Table", emu.address))
    frame, matrices = collect(manager, "Table")
    assert wait_until(lambda: len(matrices) > 20, step=frame)
    device = manager.device("Table")
    good = pairs(emu.sent)
    for got in matrices:
        assert any(np.allclose(got, expected_matrix(t, h), atol=1e-6) for t, h in good)
    assert device.bad_records > 5 and device.skipped_bytes > 5 and device.timeouts == 0
    assert device.faults == 0 and manager.status("Table").state == "running"


def test_lost_line_faults_then_samples_within_two_seconds(tmp_path, emulator, managers) -> None:
    link = tmp_path / "bus"
    emu = emulator("disconnect", disconnect_after=10, link=link)
    manager = managers(encoders("Table", str(link)))
    frame, matrices = collect(manager, "Table")
    faults_then_resumes(
        manager,
        "Table",
        emu,
        lambda: emulator("motion", link=link),
        lambda: len(matrices),
        step=frame,
    )


def test_baud_is_the_elements_where_written_and_the_buses_otherwise(emulator, managers) -> None:
    one, two = emulator("idle"), emulator("idle")
    manager = managers(
        encoders("A", one.address, "<baud>19200</baud>") + encoders("B", two.address, "")
    )
    assert not manager.pending()
    assert manager.device("A").baud == 19200 and manager.device("B").baud == 9600
