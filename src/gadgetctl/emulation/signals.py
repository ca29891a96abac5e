"""Turning SIGTERM and SIGHUP into a clean stop, as Ctrl-C already is.

Python turns SIGINT into :class:`KeyboardInterrupt`, so ``with``/``finally`` blocks undo
what an emulator made (pty links, FIFOs, sockets). SIGTERM (``kill``, ``timeout``) and
SIGHUP (the terminal closed) kill the process outright instead. Inside
:func:`stop_on_signals` they raise :class:`StopRequested` in the main thread; the signal
handler only raises (no locks are taken in it), and a repeated signal is ignored until
the block ends, so clean-up is not cut short by an impatient second ``kill``.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from types import FrameType

STOP_SIGNALS: tuple[signal.Signals, ...] = (signal.SIGTERM, signal.SIGHUP)


class StopRequested(BaseException):  # like KeyboardInterrupt: a request, not an error
    """A stop signal arrived (a BaseException, so ``except Exception`` does not swallow it)."""

    def __init__(self, signum: int) -> None:
        self.signum = signum
        super().__init__(f"stopped by {signal.Signals(signum).name}")


@contextlib.contextmanager
def stop_on_signals(signals: tuple[signal.Signals, ...] = STOP_SIGNALS) -> Iterator[None]:
    """Within the block, the first of ``signals`` raises :class:`StopRequested`; the
    previous handlers come back afterwards. Outside the main thread it does nothing."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    stopping = False

    def handler(signum: int, _frame: FrameType | None) -> None:
        nonlocal stopping
        if stopping:
            return  # already stopping: let the clean-up finish
        stopping = True
        raise StopRequested(signum)

    previous = {sig: signal.signal(sig, handler) for sig in signals}
    try:
        yield
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)
