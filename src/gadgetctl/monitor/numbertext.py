"""numpy arrays' numbers as JSON text, the text ``repr`` gives each (what the sample
records' hand formatter writes), made by one orjson call for a whole array: the shortest
digits that round-trip, as ``repr`` finds them, at a fifth of the cost for a position's
matrix. Where orjson's text could differ from ``repr``'s, none is given and the caller
formats the numbers itself."""

from __future__ import annotations

import numpy as np
import orjson

__all__ = ["array_texts"]

#: dtypes whose numbers this module writes: 64-bit floats (orjson writes other
#: widths' own shortest text, not that of the double ``tolist`` makes) and integers.
_ARRAY_DTYPES = frozenset(
    np.dtype(code) for code in ("f8", "i1", "i2", "i4", "i8", "u1", "u2", "u4", "u8")
)
#: Where orjson's text of a number may not be ``repr``'s: NaN and infinities (it writes null)
#: and magnitudes below 1e-4 (``repr`` writes an exponent, orjson decimals or ``e-7``).
_NOT_REPR = ("n", "0.0000", "e-")


def array_texts(values: np.ndarray) -> list[str] | None:
    """The JSON text of each ``values[i]`` (a number, or nested lists of them), exactly as
    :func:`~gadgetctl.monitor.records.encode_value` writes ``values[i].tolist()``; None
    where that text might differ (a non-finite number, one below 1e-4, another dtype)."""
    if values.dtype not in _ARRAY_DTYPES or values.ndim == 0:
        return None
    count = len(values)
    if not count:
        return []
    try:
        body = orjson.dumps(np.ascontiguousarray(values), option=orjson.OPT_SERIALIZE_NUMPY)
    except orjson.JSONEncodeError:
        return None
    text = body.decode("ascii")
    if any(mark in text for mark in _NOT_REPR):
        return None
    depth = values.ndim - 1
    if not depth:
        texts = text[1:-1].split(",")
    else:
        opening, closing = "[" * depth, "]" * depth
        middle = text[1 + depth : -1 - depth].split(closing + "," + opening)
        texts = [opening + part + closing for part in middle]
    return texts if len(texts) == count else None
