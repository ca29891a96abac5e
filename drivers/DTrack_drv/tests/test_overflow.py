"""Datagrams the kernel drops because the receive buffer is full are counted (the kernel's own
count, SO_RXQ_OVFL), shown with the other drops in the monitor's statistics, and end a monitor
run with exit status 1 unless loss is accepted."""

from __future__ import annotations

import socket
from pathlib import Path

import pytest
from DTrack_drv.standalone import DTrackFrame, DTrackStandalone
from DTrack_drv.wrapper import DTrackDevice

from gadgetctl.cli.monitor_run import _evaluate
from gadgetctl.input import InputManager, ManagerOptions
from gadgetctl.input.testing import wait_until
from gadgetctl.input.testing.configs import configuration
from gadgetctl.monitor.session import MonitorSession
from gadgetctl.wording import counted

pytestmark = pytest.mark.timeout(60)
EYE = "[1 0 0 0 1 0 0 0 1]"


def frame(n: int) -> bytes:
    return f"fr {n}\r\n6d 1 [0 1.0][{n} 2 3]{EYE}\r\n".encode()


def flood(port: int, first: int, count: int) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
        for n in range(first, first + count):
            tx.sendto(frame(n), ("127.0.0.1", port))


def test_the_receiver_counts_what_the_kernel_dropped() -> None:
    rx = DTrackStandalone(
        0, bind_address="127.0.0.1", receive_timeout=0.0, peer_timeout=None, receive_buffer=1
    )
    with rx:
        flood(rx.port, 1, 300)  # the smallest buffer holds a few; the rest is dropped
        frames: list[DTrackFrame] = []

        def accounted() -> bool:
            frames.extend(rx.sample_all())
            return rx.datagrams + rx.kernel_dropped == 300

        assert wait_until(accounted, timeout=5.0), (rx.datagrams, rx.kernel_dropped)
    assert rx.kernel_dropped > 0 and rx.kernel_drop_source == "ancillary"
    assert len(frames) == rx.datagrams and rx.missed_frames == rx.kernel_dropped - (
        300 - frames[-1].frame  # type: ignore[operator]
    )


def test_the_monitor_shows_kernel_drops_with_the_other_drops(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(DTrackDevice, "receive_buffer", 1)  # the kernel's smallest buffer
    config = tmp_path / "dt.jconf"
    config.write_text(
        configuration(
            "DTrack_drv", '<dtrack name="DT" version="1"><receive_port>0</receive_port></dtrack>'
        )
    )
    options = ManagerOptions(retry_interval=None, entry_points=False)
    manager, loaded = InputManager.from_files([config], options=options)
    session = MonitorSession(manager, loaded)
    try:
        session.start()
        device = manager.device("DT")
        sent = 0

        def send_burst() -> None:
            nonlocal sent
            flood(device.port, sent + 1, 500)
            sent += 500
            session.step()

        # bursts far faster than the reader, until the kernel has dropped some
        assert wait_until(lambda: device.counters["kernel_dropped"] > 0, 20.0, send_burst)

        def accounted() -> bool:
            session.step()
            counters = device.counters
            return counters["datagrams"] + counters["kernel_dropped"] == sent

        assert wait_until(accounted, timeout=10.0), (device.counters, sent)
        session.step()
        stats = session.device_stats("DT")
        assert stats is not None and device.store.dropped() == 0
        assert stats.dropped == device.counters["kernel_dropped"] > 0
        assert device.stats.dropped == stats.dropped
        assert session.final_stats()["DT"]["dropped"] == stats.dropped
        # and the run ends with exit status 1 saying so, unless loss is accepted
        _final, problems = _evaluate(session, accept_loss=False)
        assert problems == [
            f"DT: lost data: {counted(stats.dropped, 'datagram')} dropped by the kernel "
            "(receive buffer full) (--accept-loss accepts loss)"
        ]
        assert _evaluate(session, accept_loss=True)[1] == []
    finally:
        manager.shutdown()
