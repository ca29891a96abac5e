"""Scaffolding shared by the device emulators (``drivers/*/emulator.py``).

It imports nothing else from gadgetctl, so an emulator stays independent of the input
manager, as Gadgeteer drivers depend on VPR only:

* :mod:`~gadgetctl.emulation.endpoints`: the OS endpoints an emulator creates and removes:
  :class:`PseudoTerminal` (a pty pair with an optional symlink), :class:`Fifo`,
  :class:`UnixSocket`;
* :mod:`~gadgetctl.emulation.beacon`: a live emulator vouches for each path it made, so
  `gadgetctl doctor` can tell a stale link or FIFO (:func:`is_held`);
* :mod:`~gadgetctl.emulation.signals`: SIGTERM and SIGHUP stop an emulator cleanly, as
  Ctrl-C does (:func:`stop_on_signals`, :class:`StopRequested`);
* :mod:`~gadgetctl.emulation.command`: the shared command line (``--scenario``, ``--rate``,
  ``--duration`` in wall-clock seconds), the run loop (:func:`run`) and its end once the
  emulator failed or finished (:func:`ended`);
* :mod:`~gadgetctl.emulation.console`: the lines an emulator prints when a client connects
  or disconnects and when its scenario stops sending (:class:`Console`);
* :mod:`~gadgetctl.emulation.clients`: who opens and closes a device file (:class:`OpenWatch`);
* :mod:`~gadgetctl.emulation.device`: a serial device on a pty (:class:`PtyDeviceEmulator`:
  life cycle, commands, records at a rate, pause, hang-up) and its command line
  (:func:`pty_parser`, :func:`run_pty`);
* :mod:`~gadgetctl.emulation.network`: frames sent over loopback UDP at a rate
  (:class:`UdpFrameSender`) and UDP peers heard from (:class:`Peers`).
"""

from __future__ import annotations

from gadgetctl.emulation.beacon import Beacon, is_held
from gadgetctl.emulation.clients import OpenWatch
from gadgetctl.emulation.command import duration_seconds, emulator_parser, ended, run
from gadgetctl.emulation.console import Console
from gadgetctl.emulation.device import (
    STANDARD_SCENARIOS,
    PtyDeviceEmulator,
    pty_parser,
    run_pty,
)
from gadgetctl.emulation.endpoints import Fifo, PseudoTerminal, UnixSocket
from gadgetctl.emulation.network import Peers, UdpFrameSender
from gadgetctl.emulation.signals import StopRequested, stop_on_signals

__all__ = [
    "STANDARD_SCENARIOS",
    "Beacon",
    "Console",
    "Fifo",
    "OpenWatch",
    "Peers",
    "PseudoTerminal",
    "PtyDeviceEmulator",
    "StopRequested",
    "UdpFrameSender",
    "UnixSocket",
    "duration_seconds",
    "emulator_parser",
    "ended",
    "is_held",
    "pty_parser",
    "run",
    "run_pty",
    "stop_on_signals",
]
