"""The IBox protocol half and device against the emulator over a real pty pair."""

from __future__ import annotations

from pathlib import Path

import pytest
from IBox_drv.emulator import GARBAGE_CHUNKS, IBoxEmulator, encode_packet
from IBox_drv.standalone import (
    QUERY,
    IBox,
    IBoxDisconnected,
    PacketScanner,
    decode_packet,
    packet_size,
)

from gadgetctl.input.devicetypes import DigitalState
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.testing import (
    gather,
    reads_past_garbage,
    serial_line_lost_then_resumes,
    wait_until,
)
from gadgetctl.input.testing.commands import monitor_ndjson, run_gadgetctl, samples_of
from gadgetctl.input.testing.configs import corpus_copy
from gadgetctl.input.testing.fixtures import emulator_fixture, managers_fixture

pytestmark = pytest.mark.timeout(30)
FAST = {"settle": 0.0, "read_timeout": 1.0, "poll_timeout": 0.05, "poll_interval": 0.005}


emulator = emulator_fixture(IBoxEmulator, rate=500.0)
managers = managers_fixture("IBox_drv", tune={"ibox": FAST})


def test_packet_layout_and_low_bits() -> None:
    assert packet_size(0x08) == 7 and packet_size(0x2F) == 1 + 1 + 2 + 8 + 1 + 12
    packet = encode_packet(0x08, 0b0000101, (255, 0, 129, 2))
    assert packet == bytes((0x88, 0x05, 0x7F, 0x00, 0x40, 0x01, 0x50))
    decoded = decode_packet(packet)
    assert decoded is not None
    assert decoded.buttons == (1, 0, 1, 0, 0, 0, 0)  # 0/1, never the raw bit value
    assert decoded.analog == (255, 0, 129, 2)
    timed = decode_packet(encode_packet(0x21, 1, (), timer=300, encoders=(5, 16000)), 0x21)
    assert timed is not None and timed.timer == 300 and timed.encoders == (5, 16000)
    assert decode_packet(packet[:-1] + b"\x80") is None  # bit 7 inside a packet


def test_sign_on_info_strings_and_polled_packets(emulator) -> None:
    emu = emulator("motion")
    with IBox(emu.address, **FAST) as box:
        assert box.info["sign-on"] == "IBox emulator" and box.info["product id"] == "IBOX"
        assert box.info["product name"] == "Interface Box" and box.info["version"] == "2.0"
        got = gather(box.read, 30)
    assert emu.commands[:3] == [b"END", b"IMMC", b"BEGIN"]
    assert set(emu.queries) == {QUERY}
    for packet, (buttons, analog) in zip(got, emu.sent[: len(got)], strict=True):
        assert packet.analog == analog
        assert packet.buttons[:4] == tuple(buttons >> k & 1 for k in range(4))


def test_scanner_skips_junk_runs_and_counts_them() -> None:
    good = encode_packet(QUERY, 3, (10, 20, 30, 40))
    scanner = PacketScanner()
    out = scanner.feed(b"".join(GARBAGE_CHUNKS) + good + bytes(range(0x00, 0x7F)) * 5 + good)
    assert len(out) == 2 and scanner.records == 2
    assert scanner.bad_records == 2  # one run before each good packet
    assert not scanner.buffer


def test_lost_line_raises_disconnected(emulator) -> None:
    emu = emulator("disconnect", disconnect_after=15)
    with IBox(emu.address, **FAST) as box:
        got: list = []
        with pytest.raises(IBoxDisconnected):
            wait_until(lambda: False, timeout=5, step=lambda: got.extend(box.read()))
    assert len(got) == 15 and emu.disconnected.is_set()


def ibox_element(name: str, port: str) -> str:
    return (
        f'<ibox name="{name}" version="1"><port>{port}</port><min>0</min><max>255</max></ibox>\n'
        + "".join(
            f'<digital_proxy name="B{u}" version="1"><device>{name}</device><unit>{u}</unit>'
            "</digital_proxy>\n"
            for u in range(4)
        )
        + f'<analog_proxy name="A2" version="1"><device>{name}</device><unit>2</unit></analog_proxy>\n'
    )


def test_buttons_and_analogs_reach_proxies(tmp_path, emulator, managers) -> None:
    emu = emulator("buttons")
    manager = managers(ibox_element("IB", emu.address))
    assert not manager.pending()
    device = manager.device("IB")
    seen: list[tuple] = []

    def frame() -> None:
        manager.update()
        seen.extend(s.values for s in device.store.frame(DeviceKind.DIGITAL))

    assert wait_until(lambda: device.records >= 60, timeout=5, step=frame)
    assert {values for values in seen} >= {(1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1)}
    assert all(len(v) == 4 and set(v) <= {0, 1} for v in seen)
    analog = device.store.latest(DeviceKind.ANALOG).values
    assert analog == (128.0, 128.0, 128.0, 128.0)
    assert manager.proxy("A2").data == pytest.approx(128 / 255)
    states = [manager.proxy(f"B{u}").data for u in range(4)]
    assert all(isinstance(s, DigitalState) for s in states)


def test_garbage_is_counted_without_a_fault(tmp_path, emulator, managers) -> None:
    emu = emulator("garbage")
    manager = managers(ibox_element("IB", emu.address))
    device = reads_past_garbage(manager, "IB", 40)
    assert device.bad_records >= 30 and device.skipped_bytes > 0


def test_lost_line_faults_then_resumes_within_two_seconds(tmp_path, emulator, managers) -> None:
    link = tmp_path / "ibox"
    emu = emulator("disconnect", disconnect_after=20, link=link)
    manager = managers(ibox_element("IB", str(link)))
    serial_line_lost_then_resumes(
        manager, "IB", emu, lambda: emulator("motion", link=link), 20, reopened=True
    )


def corpus_powerwall(tmp_path: Path, flock_port: str, ibox_port: str) -> Path:
    return corpus_copy(
        "powerwall_18x8.jconf",
        tmp_path,
        ("<port>/dev/ttyd3</port>", f"<port>{flock_port}</port>"),
        ("<port>/dev/ttyd4</port>", f"<port>{ibox_port}</port>"),
    )


def test_powerwall_flock_and_ibox_deliver_through_proxies_and_aliases(
    tmp_path, emulator, managers
) -> None:
    from Flock_drv.emulator import FlockEmulator

    box = emulator("buttons")
    with FlockEmulator("motion", 144.0, birds=2) as flock:
        manager = managers(
            corpus_powerwall(tmp_path, flock.address, box.address),
            drivers=("Flock_drv", "IBox_drv"),
            tune={"flock": {"reset_time": 0.0, "examine_delay": 0.0}},
        )
        assert not [p for p in manager.pending() if p.name in ("IBox1", "Flock_o_Birds")]
        birds = manager.device("Flock_o_Birds")
        pressed: set[str] = set()

        def frame() -> None:
            manager.update()
            for alias in ("VJButton0", "VJButton1", "VJButton2"):
                if manager.proxy(alias).data in (DigitalState.ON, DigitalState.TOGGLE_ON):
                    pressed.add(alias)

        assert wait_until(
            lambda: len(pressed) == 3 and birds.records >= 10, timeout=10, step=frame
        ), pressed
        for alias in ("VJWand", "VJHead"):
            assert not manager.proxy(alias).stupefied


def test_gadgetctl_monitor_reads_the_powerwall(tmp_path, emulator) -> None:
    from Flock_drv.emulator import FlockEmulator

    box = emulator("motion")
    with FlockEmulator("motion", 144.0, birds=2) as flock:
        config = corpus_powerwall(tmp_path, flock.address, box.address)
        done, records = monitor_ndjson(config, duration=3, timeout=40)
    samples = samples_of(records)
    kinds = {(r.get("device"), r["kind"]) for r in samples}
    assert {("IBox1", "digital"), ("IBox1", "analog"), ("Flock_o_Birds", "position")} <= kinds, (
        done.stderr[-2000:]
    )
    for command in (["validate"], ["doctor"], ["config", "pending"]):
        out = run_gadgetctl(*command, str(config), timeout=30)
        text = out.stdout + out.stderr
        assert "DRV001" not in text, text
        assert "IBox_drv" not in text or "not found" not in text, text
