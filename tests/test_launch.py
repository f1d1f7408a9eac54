"""Item-wise kernels launched on several CPU threads give what one launch gives."""

import numpy as np
import pytest
import warp as wp

from party import launch
from party.errors import InvalidInput, WorkersLost


@wp.kernel
def _square_into(first: int, values: wp.array(dtype=float), out: wp.array(dtype=float), visits: wp.array(dtype=int)):
    i = first + wp.tid()
    out[i] = values[i] * values[i]
    visits[i] = visits[i] + 1


class Chunks(launch.Launcher):
    """A launcher that lists the chunks its item-wise launches are cut into, each a plain launch."""

    def __init__(self, settings: launch.LaunchSettings) -> None:
        super().__init__(settings)
        self.chunks = []

    def launch(self, kernel, dim, inputs, outputs=(), device=None):
        self.chunks.append((inputs[0], dim))
        wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs, device=device)


def test_chunks_cover_every_item_once(monkeypatch):
    monkeypatch.setenv("PARTY_THREADS", "3")
    launcher = Chunks(launch.LaunchSettings(min_chunk=16, split_seconds=0.0))
    chunks = launcher.chunks
    values = wp.array(np.arange(1000, dtype=np.float32), dtype=float, device="cpu")
    out = wp.zeros(1000, dtype=float, device="cpu")
    visits = wp.zeros(1000, dtype=int, device="cpu")
    for _ in range(3):  # the first launch of a kernel runs whole, the second whole and timed, the next in chunks
        launcher.launch_items(_square_into, 100, 850, [values, out, visits], "cpu")
    expected = np.where((np.arange(1000) >= 100) & (np.arange(1000) < 950), np.arange(1000.0) ** 2, 0.0)
    assert np.array_equal(out.numpy(), expected.astype(np.float32))
    assert np.array_equal(visits.numpy(), 3 * (expected > 0))
    assert sorted(chunks[2:]) == [(100, 283), (383, 283), (666, 284)]


def test_a_launch_shorter_than_a_handoff_stays_on_one_thread(monkeypatch):
    monkeypatch.setenv("PARTY_THREADS", "3")
    launcher = Chunks(launch.LaunchSettings(min_chunk=16))
    values = wp.array(np.arange(100, dtype=np.float32), dtype=float, device="cpu")
    out = wp.zeros(100, dtype=float, device="cpu")
    visits = wp.zeros(100, dtype=int, device="cpu")
    for _ in range(4):
        launcher.launch_items(_square_into, 0, 100, [values, out, visits], "cpu")
    assert [count for _, count in launcher.chunks] == [100, 100, 100, 100]


def test_a_bad_thread_count_is_one_line(monkeypatch):
    monkeypatch.setenv("PARTY_THREADS", "two")
    with pytest.raises(InvalidInput, match="^PARTY_THREADS must be a whole number of threads from 1, got 'two'$"):
        launch.thread_count()


@wp.kernel
def _scale_into(values: wp.array(dtype=float), factor: float, out: wp.array(dtype=float)):
    i = wp.tid()
    out[i] = values[i] * factor


def test_a_replayed_launch_sees_its_arrays_contents_and_not_another_calls_values():
    launcher = launch.Launcher()
    values = wp.array(np.arange(4, dtype=np.float32), dtype=float, device="cpu")
    out = wp.zeros(4, dtype=float, device="cpu")
    other = wp.zeros(4, dtype=float, device="cpu")
    launcher.launch(_scale_into, 4, [values, 2.0], [out], device="cpu")
    assert np.array_equal(out.numpy(), [0, 2, 4, 6])
    values.assign(np.full(4, 10.0, dtype=np.float32))
    launcher.launch(_scale_into, 4, [values, 2.0], [out], device="cpu")  # replayed: reads the new contents
    assert np.array_equal(out.numpy(), [20, 20, 20, 20])
    launcher.launch(_scale_into, 4, [values, 3.0], [out], device="cpu")
    assert np.array_equal(out.numpy(), [30, 30, 30, 30])
    launcher.launch(_scale_into, 2, [values, 1.0], [other], device="cpu")
    assert np.array_equal(other.numpy(), [10, 10, 0, 0])
    assert len(launcher.recorded) == 3


def test_recorded_launches_are_bounded():
    launcher = launch.Launcher(launch.LaunchSettings(max_recorded=2))
    values = wp.ones(3, dtype=float, device="cpu")
    out = wp.zeros(3, dtype=float, device="cpu")
    for factor in (1.0, 2.0, 3.0):
        launcher.launch(_scale_into, 3, [values, factor], [out], device="cpu")
    assert len(launcher.recorded) == 2
    assert np.array_equal(out.numpy(), [3, 3, 3])


@wp.kernel
def _pass_around(worker: int, workers: int, sync: launch.WorkerSync, rounds: int,
                 even: wp.array(dtype=float), odd: wp.array(dtype=float)):
    """Each round, every worker fills its share of one array from values of the other array
    that other workers wrote in the round before."""
    n = even.shape[0]
    for r in range(rounds):
        source = even
        target = odd
        if r % 2 == 1:
            source = odd
            target = even
        for i in range(n * worker // workers, n * (worker + 1) // workers):
            target[i] = 0.5 * source[(i + n // 2) % n] + source[(i + 1) % n] * 0.25 + float(i % 7)
        launch.worker_barrier(sync, workers)


@wp.kernel
def _one_stays_away(worker: int, workers: int, sync: launch.WorkerSync):
    if worker == 0:
        launch.worker_barrier(sync, workers)


@wp.func_native("""
#if !defined(__CUDA_ARCH__)
return __atomic_load_n((int*)a.data + i, __ATOMIC_ACQUIRE);
#else
return a[i];
#endif
""")
def _read_now(a: wp.array(dtype=int), i: int) -> int:
    """``a[i]`` as another thread last wrote it (a load the compiler may not hoist out of a loop)."""
    ...


@wp.kernel
def _one_arrives_late(worker: int, workers: int, sync: launch.WorkerSync, most_reads: int,
                      out: wp.array(dtype=int)):
    """Worker 1 meets worker 0 at the barrier only once worker 0, waiting there, has given its
    core away (or after ``most_reads`` looks)."""
    if worker == 1:
        reads = int(0)
        while _read_now(sync.counters, 3) == 0 and reads < most_reads:
            reads += 1
        out[0] = reads
    launch.worker_barrier(sync, workers)
    out[worker + 1] = 1


def test_workers_meeting_at_barriers_give_what_one_worker_gives():
    """Three workers each take a third of every round; a round reads values the others wrote in
    the last (a missing barrier would let a worker read stale ones)."""
    results = []
    for workers in (1, 3):
        even = wp.array(np.arange(3001, dtype=np.float32), dtype=float, device="cpu")
        odd = wp.zeros(3001, dtype=float, device="cpu")
        sync = launch.worker_sync("cpu")
        launch.launch_workers(_pass_around, workers, sync, [200, even, odd], "cpu")
        results.append(even.numpy())
        assert sync.counters.numpy().tolist()[0:3:2] == [0, 0]
    assert np.array_equal(results[0], results[1])


def test_a_worker_that_never_arrives_is_an_error_not_a_hang():
    launcher = launch.Launcher(launch.LaunchSettings(worker_spins=10000))
    sync = launch.worker_sync("cpu")
    with pytest.raises(WorkersLost, match="^_one_stays_away: a worker thread waited 10000 spins for the others; "
                                          "rerun with PARTY_THREADS=1$"):
        launcher.launch_workers(_one_stays_away, 2, sync, [], "cpu")
    assert sync.counters.numpy().tolist()[:3] == [0, 0, 0]


@pytest.mark.skipif(launch.SCHED_YIELD == 0, reason="this platform's C library has no sched_yield")
def test_a_worker_waiting_long_gives_its_core_away():
    """Worker 0 waits at the barrier until worker 1 sees it give its core away; had it only
    spun, worker 1 would arrive after 10^8 looks with no yield counted. Both then pass the
    barrier. (Beside a busy process on two cores a spinning worker held the core its partner
    needed, and the sweeps took 11 times as long.)"""
    sync = launch.worker_sync("cpu")
    out = wp.zeros(3, dtype=int, device="cpu")
    launch.launch_workers(_one_arrives_late, 2, sync, [100_000_000, out], "cpu")
    arrivals, generation, failed, yields = sync.counters.numpy().tolist()
    assert (arrivals, generation, failed) == (0, 1, 0)
    assert yields > 0
    assert out.numpy()[0] < 100_000_000
    assert out.numpy()[1:].tolist() == [1, 1]
