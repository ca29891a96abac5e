"""Sample buffers: append, swap once per frame, every sample of a frame, cap and drops."""

import threading

import numpy as np
import pytest

from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.samples import Sample, SampleBatch, SampleStore

A, D = DeviceKind.ANALOG, DeviceKind.DIGITAL


def test_samples_since_the_previous_frame_and_the_latched_newest():
    store = SampleStore([A])
    store.add(A, 1.0, (0.1,))
    store.add(A, 2.0, (0.2,))
    assert not store.frame(A)  # nothing is visible before the swap
    store.swap()
    assert [s.timestamp for s in store.frame(A)] == [1.0, 2.0]
    assert store.latest(A) == Sample(2.0, (0.2,))
    store.swap()  # a frame without samples: the frame is empty, the newest stays latched
    assert len(store.frame(A)) == 0
    assert store.latest(A) == Sample(2.0, (0.2,))


def test_batches_and_single_samples_mix_in_order():
    store = SampleStore([A, D])
    store.add(A, 0.5, (9.0,))
    store.add_batches(
        np.array([1.0, 2.0, 3.0]),
        {A: np.array([[1.0], [2.0], [3.0]]), D: np.array([[0], [1], [0]], dtype=np.int8)},
    )
    store.swap()
    frame = store.frame(A)
    assert len(frame) == 4
    assert frame.timestamps() == [0.5, 1.0, 2.0, 3.0]
    assert [float(v) for v in frame.column(0)] == [9.0, 1.0, 2.0, 3.0]
    assert store.latest(D).timestamp == 3.0 and int(store.latest(D).values[0]) == 0
    assert store.total() == 7


def test_the_cap_drops_the_oldest_samples_and_counts_them():
    store = SampleStore([A], cap=5)
    store.add_batch(A, np.arange(4.0), np.zeros((4, 1)))
    for t in range(4, 8):
        store.add(A, float(t), (float(t),))
    store.swap()
    assert store.frame(A).timestamps() == [3.0, 4.0, 5.0, 6.0, 7.0]
    assert store.dropped(A) == 3
    assert store.total(A) == 8


def test_the_most_dropped_of_any_kind():
    store = SampleStore([A, D], cap=2)
    assert store.most_dropped() == 0
    store.add_batch(A, np.arange(5.0), np.zeros((5, 1)))
    store.add_batch(D, np.arange(3.0), np.zeros((3, 1), dtype=np.int8))
    assert (store.dropped(A), store.dropped(D)) == (3, 1)
    assert store.most_dropped() == 3 == max(store.dropped(k) for k in store.kinds)
    assert SampleStore([]).most_dropped() == 0


def test_a_batch_cut_by_the_cap_keeps_its_newest_part():
    store = SampleStore([A], cap=3)
    store.add_batch(A, np.arange(10.0), np.arange(10.0).reshape(10, 1))
    store.swap()
    assert store.frame(A).timestamps() == [7.0, 8.0, 9.0]
    assert store.dropped(A) == 7


def test_unknown_kind_is_refused_with_its_name():
    store = SampleStore([A])
    with pytest.raises(KeyError, match="no digital data"):
        store.add(D, 0.0, (1,))


def test_batch_lengths_must_agree():
    with pytest.raises(ValueError):
        SampleBatch(np.arange(3.0), np.zeros((2, 1)))


@pytest.mark.timeout(10)
def test_concurrent_producer_and_swapper_lose_nothing():
    store = SampleStore([A], cap=1_000_000)
    count = 20_000
    seen: list[float] = []
    done = threading.Event()

    def produce():
        for i in range(count):
            if i % 10 == 0:
                store.add_batch(A, np.array([float(i)]), np.array([[0.0]]))
            else:
                store.add(A, float(i), (0.0,))
        done.set()

    thread = threading.Thread(target=produce)
    thread.start()
    while not done.is_set():
        store.swap()
        seen.extend(store.frame(A).timestamps())
    thread.join(5)
    store.swap()
    seen.extend(store.frame(A).timestamps())
    assert seen == [float(i) for i in range(count)]
    assert store.dropped() == 0


def test_windows_of_arrays_computed_ahead_merge_until_the_swap():
    stamps = np.arange(100.0)
    values = np.arange(100.0).reshape(100, 1)
    store = SampleStore([A], cap=50)
    store.add_slices(stamps, [(A, values)], 0, 10)
    store.add_slices(stamps, [(A, values)], 10, 25)  # continues the window: no new chunk
    store.swap()
    frame = store.frame(A)
    assert len(frame.chunks) == 1 and frame.timestamps() == [float(t) for t in range(25)]
    assert store.latest(A).timestamp == 24.0 and float(store.latest(A).values[0]) == 24.0
    store.add_slices(stamps, [(A, values)], 25, 90)  # more than the cap between two swaps
    store.swap()
    assert store.frame(A).timestamps() == [float(t) for t in range(40, 90)]
    assert store.dropped(A) == 15 and store.total(A) == 90


def test_kinds_given_by_value_or_member():
    assert SampleStore(["analog", D]).kinds == (A, D)
    with pytest.raises(ValueError):
        SampleStore(["no such kind"])


def test_a_kind_has_a_channel_only_once_a_sample_of_it_came():
    store = SampleStore([A, D, DeviceKind.POSITION])
    assert store.channels_made == ()
    # a declared kind without samples reads as empty, as before
    assert store.frame(D).count == 0 and store.latest(D) is None
    assert (store.total(D), store.dropped(D), store.total(), store.most_dropped()) == (0, 0, 0, 0)
    store.add("analog", 1.0, (0.5,))  # by value: the channel is the member's
    store.add_batch(DeviceKind.POSITION, np.array([2.0]), np.zeros((1, 1, 4, 4)))
    store.swap()
    assert store.channels_made == (A, DeviceKind.POSITION)
    assert store.kinds == (A, D, DeviceKind.POSITION)
    assert store.frame(A).timestamps() == [1.0] and store.latest(A).timestamp == 1.0
    assert store.total() == 2 and store.total(D) == 0
    assert store.frame(D).count == 0  # still no digital channel, nothing shared was changed
    assert store.channels_made == (A, DeviceKind.POSITION)
    with pytest.raises(KeyError, match="no hat data"):
        store.frame(DeviceKind.HAT)
    with pytest.raises(KeyError, match="no hat data"):
        store.add_slices(np.array([3.0]), ((DeviceKind.HAT, np.zeros((1, 1))),), 0, 1)


def test_stores_of_the_same_kinds_share_one_tuple_of_them():
    assert SampleStore([A, D]).kinds is SampleStore(["analog", "digital"]).kinds


def test_a_tuple_of_kinds_given_again_reads_as_the_first_time():
    given = (A, D)
    first = SampleStore(given).kinds
    assert SampleStore(given).kinds is first  # (taken from what the first store made)
    assert SampleStore(("analog", "digital")).kinds is first
    other = ("digital", "analog")  # another tuple, other kinds in another order
    assert SampleStore(other).kinds == (D, A)
    assert SampleStore(other).kinds is SampleStore([D, A]).kinds
    assert all(type(k) is DeviceKind for k in SampleStore(other).kinds)


def test_the_newest_of_a_shared_window_not_taken_in_yet_is_read_from_it():
    from gadgetctl.input.samples import SharedWindows

    P = DeviceKind.POSITION
    stores = [SampleStore([A, D, P]) for _ in range(2)]
    windows = SharedWindows(stores)
    stamps = np.array([1.0, 2.0, 3.0])
    items = ((A, np.array([[0.1], [0.2], [0.3]])),)
    for slot in (0, 1):
        windows.set_arrays(slot, stamps, items)
    windows.publish(5.0, windows.every, np.array([0, 0]), np.array([2, 1]))
    windows.publish(  # a frame with nothing new for either: the windows above stay the newest
        6.0, np.empty(0, np.int64), np.empty(0, np.int64), np.empty(0, np.int64), np.array([0, 1])
    )
    newest = stores[0].newest()  # read without taking the window in (the kinds never filled
    assert [kind for kind, _ in newest] == [A]  # are not asked)
    assert newest[0][1].timestamp == 2.0 and float(newest[0][1].values[0]) == 0.2
    assert stores[1].latest(A).timestamp == 1.0 and stores[1].latest(D) is None
    for store in stores:  # taken in, the same
        store.sync()
    assert stores[0].latest(A).timestamp == 2.0 and stores[1].latest(A).timestamp == 1.0
    assert [kind for kind, _ in stores[1].newest()] == [A]
    assert stores[0].total(A) == 2 and stores[1].total(A) == 1
