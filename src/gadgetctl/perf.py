"""Keeping bulk work fast.

Validation builds many small objects that all live until the end of the run, and creates
almost no garbage cycles. Python's cyclic garbage collector would walk the growing heap
over and over, which makes large runs slower than linear (about 1.4 times at fifty copies
of the VR Juggler corpus) while freeing nothing; measured peak memory is the same without
it. So it is paused for the duration of such work and its previous state restored after.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def collector_paused() -> Iterator[None]:
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        # Switched back on, the collector would soon walk everything built meanwhile (a
        # tenth of a second after a check of 50,000 elements). A process that ends without
        # teardown (see retain_until_exit) frees nothing more that matters: left off there.
        if was_enabled and _retained is None:
            gc.enable()


@contextmanager
def built_to_last() -> Iterator[None]:
    """:func:`collector_paused` for work whose results live to the end of a process that ends
    without teardown (a monitor's checked configuration, its devices and proxies): at the
    end, every object alive is left out of the collector's later passes (``gc.freeze``)
    before it is switched on again. The collector goes on collecting what is made
    afterwards; it no longer walks these (10,000 devices' objects were walked by four
    collections that followed the check and the configuration, 0.15-0.2 s in all). Only
    for such a process: what is set aside is never freed."""
    with collector_paused():
        yield
        gc.freeze()


#: What :func:`retain` keeps, once :func:`retain_until_exit` was called (else None).
_retained: list[object] | None = None


def retain_until_exit() -> None:
    """Called by a command that ends its process without teardown (``os._exit``, see
    :mod:`gadgetctl.cli.exiting`): from now on :func:`retain` keeps what it is given."""
    global _retained
    if _retained is None:
        _retained = []


def retain(obj: object) -> None:
    """Keep ``obj`` to the end of the process when the process ends without teardown:
    freeing the objects of a validation of 50,000 elements one by one, right before the
    process ends anyway, costs a tenth of its time. Otherwise nothing: a library caller
    gets the memory back as usual."""
    if _retained is not None:
        _retained.append(obj)
