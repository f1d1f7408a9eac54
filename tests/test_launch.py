"""Item-wise kernels launched on several CPU threads give what one launch gives."""

import numpy as np
import pytest
import warp as wp

from party import launch
from party.errors import InvalidInput


@wp.kernel
def _square_into(first: int, values: wp.array(dtype=float), out: wp.array(dtype=float), visits: wp.array(dtype=int)):
    i = first + wp.tid()
    out[i] = values[i] * values[i]
    visits[i] = visits[i] + 1


@pytest.fixture
def small_chunks(monkeypatch):
    monkeypatch.setattr(launch, "MIN_CHUNK", 16)
    monkeypatch.setattr(launch, "SPLIT_SECONDS", 0.0)
    monkeypatch.setattr(launch, "_item_seconds", {})
    monkeypatch.setattr(launch, "_loaded", set())
    monkeypatch.setenv("PARTY_THREADS", "3")


def test_chunks_cover_every_item_once(small_chunks, monkeypatch):
    chunks = []
    monkeypatch.setattr(launch, "launch", lambda kernel, count, inputs, device: (
        chunks.append((inputs[0], count)), wp.launch(kernel, dim=count, inputs=inputs, device=device)))
    values = wp.array(np.arange(1000, dtype=np.float32), dtype=float, device="cpu")
    out = wp.zeros(1000, dtype=float, device="cpu")
    visits = wp.zeros(1000, dtype=int, device="cpu")
    for _ in range(3):  # the first launch of a kernel runs whole, the second whole and timed, the next in chunks
        launch.launch_items(_square_into, 100, 850, [values, out, visits], "cpu")
    expected = np.where((np.arange(1000) >= 100) & (np.arange(1000) < 950), np.arange(1000.0) ** 2, 0.0)
    assert np.array_equal(out.numpy(), expected.astype(np.float32))
    assert np.array_equal(visits.numpy(), 3 * (expected > 0))
    assert sorted(chunks[2:]) == [(100, 283), (383, 283), (666, 284)]


def test_a_launch_shorter_than_a_handoff_stays_on_one_thread(monkeypatch):
    monkeypatch.setattr(launch, "MIN_CHUNK", 16)
    monkeypatch.setattr(launch, "_item_seconds", {})
    monkeypatch.setattr(launch, "_loaded", set())
    monkeypatch.setenv("PARTY_THREADS", "3")
    chunks = []
    monkeypatch.setattr(launch, "launch", lambda kernel, count, inputs, device: (
        chunks.append(count), wp.launch(kernel, dim=count, inputs=inputs, device=device)))
    values = wp.array(np.arange(100, dtype=np.float32), dtype=float, device="cpu")
    out = wp.zeros(100, dtype=float, device="cpu")
    visits = wp.zeros(100, dtype=int, device="cpu")
    for _ in range(4):
        launch.launch_items(_square_into, 0, 100, [values, out, visits], "cpu")
    assert chunks == [100, 100, 100, 100]


def test_a_bad_thread_count_is_one_line(monkeypatch):
    monkeypatch.setenv("PARTY_THREADS", "two")
    with pytest.raises(InvalidInput, match="^PARTY_THREADS must be a whole number, got 'two'$"):
        launch.thread_count()


@wp.kernel
def _scale_into(values: wp.array(dtype=float), factor: float, out: wp.array(dtype=float)):
    i = wp.tid()
    out[i] = values[i] * factor


def test_a_replayed_launch_sees_its_arrays_contents_and_not_another_calls_values(monkeypatch):
    monkeypatch.setattr(launch, "_recorded", launch.OrderedDict())
    values = wp.array(np.arange(4, dtype=np.float32), dtype=float, device="cpu")
    out = wp.zeros(4, dtype=float, device="cpu")
    other = wp.zeros(4, dtype=float, device="cpu")
    launch.launch(_scale_into, 4, [values, 2.0], [out], device="cpu")
    assert np.array_equal(out.numpy(), [0, 2, 4, 6])
    values.assign(np.full(4, 10.0, dtype=np.float32))
    launch.launch(_scale_into, 4, [values, 2.0], [out], device="cpu")  # replayed: reads the new contents
    assert np.array_equal(out.numpy(), [20, 20, 20, 20])
    launch.launch(_scale_into, 4, [values, 3.0], [out], device="cpu")
    assert np.array_equal(out.numpy(), [30, 30, 30, 30])
    launch.launch(_scale_into, 2, [values, 1.0], [other], device="cpu")
    assert np.array_equal(other.numpy(), [10, 10, 0, 0])
    assert len(launch._recorded) == 3


def test_recorded_launches_are_bounded(monkeypatch):
    monkeypatch.setattr(launch, "_recorded", launch.OrderedDict())
    monkeypatch.setattr(launch, "MAX_RECORDED", 2)
    values = wp.ones(3, dtype=float, device="cpu")
    out = wp.zeros(3, dtype=float, device="cpu")
    for factor in (1.0, 2.0, 3.0):
        launch.launch(_scale_into, 3, [values, factor], [out], device="cpu")
    assert len(launch._recorded) == 2
    assert np.array_equal(out.numpy(), [3, 3, 3])
