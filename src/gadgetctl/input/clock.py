"""The clock every timestamp of the input manager comes from.

Timestamps are seconds of :func:`time.perf_counter` (monotonic, high resolution), so they
can be compared with each other but not with wall-clock time.
"""

from __future__ import annotations

import time

now = time.perf_counter
