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
        if was_enabled:
            gc.enable()
