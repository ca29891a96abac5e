"""numpy arrays' numbers written by orjson (gadgetctl.monitor.numbertext) must be the text
the sample records' own formatter writes (``repr`` of each number), or not be given at all:
a recording's bytes do not depend on which path wrote them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from gadgetctl.input.devicetypes import Analog
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.samples import FrameSamples, SampleBatch
from gadgetctl.monitor.encoding import encode_array_rows, encode_frame
from gadgetctl.monitor.numbertext import array_texts
from gadgetctl.monitor.records import decode_line, encode_rows, encode_value

pytestmark = pytest.mark.timeout(120)

#: Numbers where orjson's text and ``repr``'s part: tiny magnitudes, exponents, non-finite.
AWKWARD = [
    0.0,
    -0.0,
    1.0,
    0.5,
    1e-4,
    9.99e-5,
    1e-5,
    -2.5e-7,
    5e-324,
    1e15,
    1e16,
    1.5e17,
    1e300,
    22551.723568755,
    0.1 + 0.2,
    math.nan,
    math.inf,
    -math.inf,
]


def _reference(values: np.ndarray) -> list[str]:
    return [encode_value(v) for v in values.tolist()]


@pytest.mark.parametrize("number", AWKWARD)
def test_each_number_is_repr_or_left_to_the_caller(number):
    texts = array_texts(np.array([number, 1.0]))
    if texts is None:
        assert not math.isfinite(number) or 0 < abs(number) < 1e-4
    else:
        assert texts == _reference(np.array([number, 1.0]))


floats = st.floats(allow_nan=True, allow_infinity=True, width=64)
shapes = st.sampled_from([(3,), (2, 1), (4, 1, 4, 4), (2, 3, 4, 4), (5, 2, 3), (1, 1, 0)])


@settings(max_examples=300, deadline=None)
@given(data=st.data())
def test_array_texts_match_the_hand_formatter_or_give_none(data):
    shape = data.draw(shapes)
    dtype = data.draw(st.sampled_from(["f8", "i8", "i4", "u1"]))
    elements = floats if dtype == "f8" else None
    values = data.draw(hnp.arrays(dtype, shape, elements=elements))
    texts = array_texts(values)
    if texts is not None:
        assert texts == _reference(values)
    elif dtype != "f8":
        pytest.fail(f"integers are always written: {values!r}")
    else:
        flat = values.ravel()
        assert (~np.isfinite(flat) | ((flat != 0) & (np.abs(flat) < 1e-4))).any()


@pytest.mark.parametrize("dtype", ["f4", "f2", "?", "c16", "U3"])
def test_other_dtypes_are_left_to_the_caller(dtype):
    # float32's own shortest text is not that of the double tolist() makes (0.1 -> 0.1 vs
    # 0.10000000149011612): only doubles and integers are written here
    assert array_texts(np.zeros((2, 1), dtype=dtype)) is None


@pytest.mark.parametrize(
    "values",
    [
        np.arange(12, dtype="<i4").reshape(3, 4)[:, ::2],  # not contiguous
        (np.arange(16.0) / 3).reshape(4, 4).T,
        np.arange(8, dtype=">i8").reshape(4, 2),  # not this machine's byte order
        (np.arange(6.0) / 7).astype(">f8").reshape(3, 2),
    ],
    ids=["strided", "transposed", "big-endian-ints", "big-endian-doubles"],
)
def test_arrays_as_they_come_are_written_as_their_numbers(values):
    assert array_texts(values) == _reference(values)


@settings(max_examples=200, deadline=None)
@given(data=st.data())
def test_encode_array_rows_writes_what_encode_rows_writes(data):
    count = data.draw(st.integers(1, 5))  # (one sample: its timestamp by repr)
    inner = data.draw(st.sampled_from([(), (4, 4), (3,)]))
    units = data.draw(st.integers(1, 3))
    stamps = data.draw(hnp.arrays("f8", (count,), elements=st.floats(0, 1e6, allow_nan=False)))
    values = data.draw(hnp.arrays("f8", (count, units, *inner), elements=floats))
    text = encode_array_rows("Head", "position", stamps, values)
    expected = encode_rows("Head", "position", stamps.tolist(), values.tolist())
    if text is not None:
        assert text == expected
        assert len([decode_line(line) for line in text.splitlines()]) == count * units


def test_a_position_frame_is_written_by_orjson_and_reads_back_exactly():
    rng = np.random.default_rng(7)
    matrices = rng.normal(size=(6, 2, 4, 4))
    stamps = 1000.0 + np.cumsum(rng.random(6))
    frame = FrameSamples([SampleBatch(stamps, matrices)])
    assert encode_array_rows("Head", "position", stamps, matrices) is not None
    text, count = encode_frame("Head", DeviceKind.POSITION, frame, Analog())
    assert count == 12
    assert text == encode_rows("Head", "position", stamps.tolist(), matrices.tolist())
    back = [decode_line(line) for line in text.splitlines()]
    read = np.array([r.value for r in back]).reshape(matrices.shape)
    assert np.array_equal(read, matrices)  # every double exactly
    assert [r.timestamp for r in back[::2]] == stamps.tolist()


def test_a_frame_with_a_non_finite_value_is_written_as_the_hand_formatter_writes_it():
    values = np.array([[0.5], [math.nan], [math.inf]])
    stamps = np.array([1.0, 2.0, 3.0])
    assert encode_array_rows("Dial", "hat", stamps, values) is None
    text, _ = encode_frame(
        "Dial", DeviceKind.HAT, FrameSamples([SampleBatch(stamps, values)]), Analog()
    )
    assert '"value":NaN' in text and '"value":Infinity' in text


@settings(max_examples=200, deadline=None)
@given(data=st.data())
def test_analog_rows_with_raw_values_are_what_encode_rows_writes(data):
    count = data.draw(st.integers(1, 4))
    units = data.draw(st.integers(1, 3))
    stamps = data.draw(hnp.arrays("f8", (count,), elements=st.floats(1.0, 1e6, allow_nan=False)))
    raw_dtype = data.draw(st.sampled_from(["f8", "i2", "i8"]))
    raw = data.draw(
        hnp.arrays(raw_dtype, (count, units), elements=floats if raw_dtype == "f8" else None)
    )
    # the value: the raw one normalised, or itself (a raw value equal to its value is left out)
    values = data.draw(
        st.sampled_from(
            [np.clip(raw.astype("f8"), 0.0, 1.0), raw.astype("f8"), np.zeros((count, units))]
        )
    )
    text = encode_array_rows("Stick", "analog", stamps, values, raw)
    expected = encode_rows("Stick", "analog", stamps.tolist(), values.tolist(), raw.tolist())
    if text is not None:
        assert text == expected
    elif raw_dtype != "f8":
        assert not np.isfinite(values).all() or ((values != 0) & (np.abs(values) < 1e-4)).any()


def test_an_analog_frame_writes_raw_values_only_where_they_differ():
    stick = Analog()
    stick.analog_min, stick.analog_max = -1.0, 1.0
    raw = np.array([[-1.0, 0.5], [1.0, 3.0]])
    stamps = np.array([10.0, 10.5])
    text, count = encode_frame(
        "Stick", DeviceKind.ANALOG, FrameSamples([SampleBatch(stamps, raw)]), stick
    )
    assert count == 4
    normalised = (np.clip(raw, -1.0, 1.0) + 1.0) / 2.0
    assert encode_array_rows("Stick", "analog", stamps, normalised, raw) is not None
    assert text == encode_rows(
        "Stick", "analog", stamps.tolist(), normalised.tolist(), raw.tolist()
    )
    records = [decode_line(line) for line in text.splitlines()]
    assert [(r.value, r.raw) for r in records] == [(0.0, -1.0), (0.75, 0.5), (1.0, 1.0), (1.0, 3.0)]
    assert text.count('"raw"') == 3  # 1.0 normalises to itself: no raw written
