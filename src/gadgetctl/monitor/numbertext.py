"""numpy arrays' numbers as JSON text, the text ``repr`` gives each (what the sample
records' hand formatter writes), made by one orjson call for a whole array: the shortest
digits that round-trip, as ``repr`` finds them, at a fifth of the cost for a position's
matrix. Where orjson's text could differ from ``repr``'s, none is given and the caller
formats the numbers itself."""

from __future__ import annotations

import numpy as np
import orjson

__all__ = ["array_texts"]

#: The dtypes (by character code) whose numbers this module writes: doubles (orjson writes
#: other floats' own shortest text, not that of the double ``tolist`` makes) and integers.
_WRITTEN = frozenset("dbhilqBHILQ")


def array_texts(values: np.ndarray) -> list[str] | None:
    """The JSON text of each ``values[i]`` (a number, or nested lists of them), exactly as
    :func:`~gadgetctl.monitor.records.encode_value` writes ``values[i].tolist()``; None
    where that text might differ (a non-finite number, one below 1e-4, another dtype)."""
    if values.dtype.char not in _WRITTEN or not values.ndim:
        return None
    count = len(values)
    if not count:
        return []
    try:
        body = orjson.dumps(values, option=orjson.OPT_SERIALIZE_NUMPY)
    except orjson.JSONEncodeError:  # not C-contiguous, or not in this machine's byte order
        try:
            body = orjson.dumps(
                np.ascontiguousarray(values, dtype=values.dtype.newbyteorder("=")),
                option=orjson.OPT_SERIALIZE_NUMPY,
            )
        except orjson.JSONEncodeError:
            return None
    text = body.decode("ascii")
    # where orjson's text may not be repr's: NaN and infinities (orjson writes null) and
    # magnitudes below 1e-4 (repr writes an exponent; orjson decimals, or one like 2.5e-7)
    if "n" in text or "0.0000" in text or "e-" in text:
        return None
    depth = values.ndim - 1
    if not depth:
        texts = text[1:-1].split(",")
    else:
        opening, closing = "[" * depth, "]" * depth
        middle = text[1 + depth : -1 - depth].split(closing + "," + opening)
        texts = [opening + part + closing for part in middle]
    return texts if len(texts) == count else None
