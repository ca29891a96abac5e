"""The VRPN driver's emulators.

:func:`main` (what `gadgetctl emulate VRPN_drv` runs) serves gadgetctl waveform devices
named ``Tracker0``, ``Button0`` and ``Analog0`` with `gadgetctl serve`, so the example
configuration and any VRPN client read them as from a VRPN server.

:class:`VrpnEmulator` is a small scripted VRPN server for the driver's tests: a tracker, a
button device and an analog device whose data are pure functions of the frame number,
served with gadgetctl's VRPN server (:class:`gadgetctl.vrpn.VrpnServer`).

Devices (names configurable): ``Tracker0`` with ``sensors`` sensors moving on circles,
``Button0`` with ``buttons`` buttons, ``Analog0`` with ``channels`` channels in [-1, 1].
Scenarios: ``idle`` (everything at rest), ``motion`` (poses and analogs move, buttons still)
and ``buttons`` (``motion``, and the buttons are pressed and released one after the other);
``silent``: the devices are announced and answer pings, but report nothing.
Tracker reports go unreliable (by UDP to lob clients, as the C++ tracker sends them);
buttons reliable, with the button states sent on every connection and ping.

Run ``python emulator.py --help`` (or ``gadgetctl emulate VRPN_drv``) for the command line.
"""

from __future__ import annotations

import math
import sys
import threading
import time

from gadgetctl.emulation import Console
from gadgetctl.emulation.command import EmulatorArgumentParser
from gadgetctl.vrpn import VrpnServer, codecs

SCENARIOS = ("idle", "motion", "buttons", "silent")


# -- the scenario's data (pure functions, so tests can compute what to expect) ----------------


def sensor_pose(
    frame: int, sensor: int, moving: bool
) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
    """Position (metres) and (x, y, z, w) quaternion of ``sensor`` at ``frame``."""
    t = frame if moving else 0
    angle = 0.05 * t + sensor
    position = (0.5 * math.cos(angle) + sensor, 1.5 + 0.1 * sensor, 0.5 * math.sin(angle))
    half = 0.5 * angle  # a turn about the vertical axis
    return position, (0.0, math.sin(half), 0.0, math.cos(half))


def button_states(frame: int, buttons: int, scenario: str) -> tuple[int, ...]:
    """Button ``(frame // 10) % buttons`` is pressed during the first half of each 10 frames."""
    states = [0] * buttons
    if scenario == "buttons" and buttons and frame % 10 < 5:
        states[(frame // 10) % buttons] = 1
    return tuple(states)


def analog_values(frame: int, channels: int, moving: bool) -> tuple[float, ...]:
    t = frame if moving else 0
    return tuple(math.sin(0.05 * t + 0.7 * c) for c in range(channels))


class VrpnEmulator:
    """Serves the three devices at ``rate`` frames per second until :meth:`stop`."""

    def __init__(
        self,
        port: int = 3883,
        *,
        host: str = "127.0.0.1",
        scenario: str = "motion",
        rate: float = 60.0,
        sensors: int = 2,
        buttons: int = 4,
        channels: int = 2,
        tracker: str = "Tracker0",
        button: str = "Button0",
        analog: str = "Analog0",
    ) -> None:
        if scenario not in SCENARIOS:
            raise ValueError(f"unknown scenario {scenario!r} (one of {', '.join(SCENARIOS)})")
        if rate <= 0 or min(sensors, buttons, channels) < 0:
            raise ValueError("the rate must be positive and the counts not negative")
        if buttons > codecs.MAX_BUTTONS or channels > codecs.MAX_CHANNELS:
            raise ValueError(
                f"at most {codecs.MAX_BUTTONS} buttons and {codecs.MAX_CHANNELS} channels"
            )
        self.scenario, self.rate = scenario, rate
        self.sensors, self.buttons, self.channels = sensors, buttons, channels
        self.server = VrpnServer(host, port)
        s = self.server
        self._tracker = s.register_sender(tracker) if sensors else None
        self._button = s.register_sender(button) if buttons else None
        self._analog = s.register_sender(analog) if channels else None
        self._pose_type = s.register_type(codecs.TRACKER_POS_QUAT)
        self._change_type = s.register_type(codecs.BUTTON_CHANGE)
        self._states_type = s.register_type(codecs.BUTTON_STATES)
        self._analog_type = s.register_type(codecs.ANALOG_CHANNEL)
        s.on_connect = self._connected
        s.on_disconnect = self._disconnected
        s.on_ping = lambda client, name: self._send_states(client) if name == button else None
        self.frame = 0
        self._states = button_states(0, buttons, scenario)
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self.error: BaseException | None = None
        self.console = Console()

    @property
    def port(self) -> int:
        return self.server.port

    @property
    def address(self) -> str:
        return f"127.0.0.1:{self.server.port}"

    def start(self) -> VrpnEmulator:
        self.server.start()
        self._stop.clear()
        self._threads = [
            threading.Thread(target=self._serve, name="vrpn-emulator-io", daemon=True),
            threading.Thread(target=self._tick_loop, name="vrpn-emulator-ticks", daemon=True),
        ]
        for t in self._threads:
            t.start()
        return self

    def stop(self, timeout: float = 2.0) -> None:
        self._stop.set()
        for t in self._threads:
            t.join(timeout)
        self.server.close()

    def __enter__(self) -> VrpnEmulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _serve(self) -> None:
        try:
            self.server.serve_forever(self._stop, 0.02)
        except BaseException as exc:  # reported by main()
            self.error = exc

    def _connected(self, client) -> None:
        self.console.client_connected(f"{client.address[0]}:{client.address[1]}")
        self._send_states(client)

    def _disconnected(self, client, reason: str) -> None:
        self.console.client_disconnected(f"{client.address[0]}:{client.address[1]}", reason)

    def _send_states(self, client) -> None:
        if self._button is not None:
            self.server.send_to(
                client, self._button, self._states_type, codecs.encode_button_states(self._states)
            )

    def _tick_loop(self) -> None:
        period = 1.0 / self.rate
        next_at = time.monotonic()
        try:
            while not self._stop.is_set():
                self.tick()
                next_at += period
                delay = next_at - time.monotonic()
                if delay > 0:
                    self._stop.wait(delay)
                else:
                    next_at = time.monotonic()
        except BaseException as exc:
            self.error = exc

    def tick(self) -> None:
        """Send one frame: every sensor's pose, button changes, the analog channels."""
        if self.scenario == "silent":
            return
        n, s, moving = self.frame, self.server, self.scenario != "idle"
        stamp = time.time()
        if self._tracker is not None:
            for sensor in range(self.sensors):
                position, quat = sensor_pose(n, sensor, moving)
                s.send(
                    self._tracker,
                    self._pose_type,
                    codecs.encode_pose(sensor, position, quat),
                    timestamp=stamp,
                    reliable=False,
                    flush=False,
                )
        if self._button is not None:
            states = button_states(n, self.buttons, self.scenario)
            for i, (old, new) in enumerate(zip(self._states, states, strict=True)):
                if old != new:
                    s.send(
                        self._button,
                        self._change_type,
                        codecs.encode_button_change(i, new),
                        timestamp=stamp,
                        flush=False,
                    )
            self._states = states
        if self._analog is not None:
            s.send(
                self._analog,
                self._analog_type,
                codecs.encode_analog(analog_values(n, self.channels, moving)),
                timestamp=stamp,
                reliable=False,
                flush=False,
            )
        s.flush()
        self.frame += 1


WAVEFORM_PATHS = ("circle", "figure_eight", "spin")
WAVEFORM_SHAPES = ("sine", "triangle", "square")


def waveform_configuration(
    *,
    sensors: int,
    buttons: int,
    channels: int,
    rate: float,
    tracker: str = "Tracker0",
    button: str = "Button0",
    analog: str = "Analog0",
) -> str:
    """A configuration of gadgetctl waveform devices named as VRPN devices: ``tracker``
    with ``sensors`` positions, ``button`` with ``buttons`` buttons, ``analog`` with
    ``channels`` channels in [-1, 1] (a device with a count of 0 is left out)."""

    def device(name: str, body: list[str]) -> str:
        lines = [f"<rate>{rate:g}</rate>", "<event_period>0.0</event_period>", *body]
        return (
            f'      <waveform_device name="{name}" version="1">\n'
            + "".join(f"         {line}\n" for line in lines)
            + "      </waveform_device>\n"
        )

    parts = []
    if sensors:
        parts.append(
            device(
                tracker,
                [f"<position_path>{WAVEFORM_PATHS[i % 3]}</position_path>" for i in range(sensors)]
                + [f"<position_period>{4.0 + i:g}</position_period>" for i in range(sensors)],
            )
        )
    if buttons:
        parts.append(
            device(
                button,
                [f"<button_period>{1.0 + 0.5 * i:g}</button_period>" for i in range(buttons)],
            )
        )
    if channels:
        parts.append(
            device(
                analog,
                [
                    f"<analog_waveform>{WAVEFORM_SHAPES[i % 3]}</analog_waveform>"
                    for i in range(channels)
                ]
                + [
                    f"<analog_frequency>{0.5 / (i + 1):g}</analog_frequency>"
                    for i in range(channels)
                ]
                + ["<min>-1.0</min>", "<max>1.0</max>"],
            )
        )
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>\n'
        '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" '
        'name="VRPN_drv emulator">\n   <elements>\n'
        + "".join(parts)
        + "   </elements>\n</configuration>\n"
    )


def main(argv: list[str] | None = None) -> int:
    """`gadgetctl emulate VRPN_drv`: gadgetctl waveform devices served over VRPN by
    `gadgetctl serve` (Tracker0, Button0, Analog0 as the example configuration reads them)."""
    import tempfile
    from pathlib import Path

    parser = EmulatorArgumentParser(
        prog="gadgetctl emulate VRPN_drv",
        description="Serve waveform devices over VRPN with gadgetctl serve: Tracker0 (circles, "
        "figure-eights, spins), Button0 (square-wave buttons), Analog0 (sine, "
        "triangle and square channels in [-1, 1]).",
    )
    parser.add_argument(
        "--port", type=int, default=3883, help="TCP and UDP port (default 3883; 0 = any)"
    )
    parser.add_argument(
        "--bind", default="127.0.0.1", help="address to listen on (default 127.0.0.1)"
    )
    parser.add_argument(
        "--rate", type=float, default=100.0, help="samples per second of every device (default 100)"
    )
    parser.add_argument("--duration", type=float, help="stop after this many seconds")
    parser.add_argument("--sensors", type=int, default=2, help="tracker sensors (default 2)")
    parser.add_argument("--buttons", type=int, default=4, help="buttons (default 4)")
    parser.add_argument("--channels", type=int, default=2, help="analog channels (default 2)")
    parser.add_argument(
        "--format", choices=("text", "json"), default="text", help="output of serve"
    )
    args = parser.parse_args(argv)
    if not 0 < args.rate <= 100_000:
        parser.error(
            f"--rate must be more than 0 and at most 100000 samples per second, not {args.rate:g}"
        )
    if (
        min(args.sensors, args.buttons, args.channels) < 0
        or args.buttons > codecs.MAX_BUTTONS
        or args.channels > codecs.MAX_CHANNELS
    ):
        parser.error(
            f"counts are 0 or more, at most {codecs.MAX_BUTTONS} buttons and "
            f"{codecs.MAX_CHANNELS} channels"
        )
    if not (args.sensors or args.buttons or args.channels):
        parser.error("nothing to serve: give a sensor, button or channel count above 0")
    from gadgetctl.cli.main import main as gadgetctl

    with tempfile.TemporaryDirectory(prefix="gadgetctl-vrpn-emulator-") as tmp:
        config = Path(tmp) / "vrpn-emulator.jconf"
        config.write_text(
            waveform_configuration(
                sensors=args.sensors, buttons=args.buttons, channels=args.channels, rate=args.rate
            )
        )
        command = [
            "serve",
            str(config),
            "--port",
            str(args.port),
            "--bind",
            args.bind,
            "--format",
            args.format,
        ]
        if args.duration is not None:
            command += ["--duration", str(args.duration)]
        try:
            gadgetctl(command)
        except SystemExit as exit_:
            return exit_.code if isinstance(exit_.code, int) else (0 if exit_.code is None else 1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
