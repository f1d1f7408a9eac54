"""The axis interval lists of section 6.1 against brute force."""

import numpy as np
import warp as wp
from hypothesis import given, settings, strategies as st

from party.collision.intervals import AxisIntervalLists, broad_phase


def brute_force(lo, hi, tri_lo, tri_hi):
    return set(np.where(np.all(tri_lo <= hi, axis=1) & np.all(lo <= tri_hi, axis=1))[0])


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), count=st.integers(1, 300), scale=st.floats(0.01, 0.3),
       min_cell=st.floats(0.005, 0.2))
def test_candidates_are_a_superset_of_brute_force_hits_within_the_min_rule(seed, count, scale, min_cell):
    rng = np.random.default_rng(seed)
    points = rng.uniform(-1, 1, (count, 3)).repeat(3, axis=0) + rng.normal(0, scale, (3 * count, 3))
    tris = np.arange(3 * count, dtype=np.int32).reshape(count, 3)
    velocities = rng.normal(0, 1, (3 * count, 3))
    dt, margin = 0.01, 0.002
    lists = AxisIntervalLists(wp.array(tris, dtype=int, device="cpu"), min_cell=min_cell, max_cells=64, spans_per_item=1)
    lists.build_checked(wp.array(points, dtype=wp.vec3, device="cpu"), wp.array(velocities, dtype=wp.vec3, device="cpu"), dt, margin)

    start = rng.uniform(-1.2, 1.2, (40, 3))
    step = rng.normal(0, 0.05, (40, 3))
    lo = np.minimum(start, start + step) - 0.003
    hi = np.maximum(start, start + step) + 0.003
    found, walked = broad_phase(lists, lo, hi)

    end = points + velocities * dt
    tri_lo = np.minimum(points, end).reshape(count, 3, 3).min(axis=1) - margin
    tri_hi = np.maximum(points, end).reshape(count, 3, 3).max(axis=1) + margin
    host = lists.host_lists()
    for q in range(len(lo)):
        hits = brute_force(lo[q], hi[q], tri_lo, tri_hi)
        got = list(found[q])
        assert len(got) == len(set(got))  # each triangle once
        assert set(got) == hits  # superset of the true hits, and box-checked in 3-D
        assert len(got) <= walked[q] or not hits
        # walked is n = min(n_x, n_y, n_z) of list entries under the query box
        counts = []
        for axis in range(3):
            if hi[q, axis] < host["bounds"][axis] or lo[q, axis] > host["bounds"][axis + 3]:
                counts.append(0)
                continue
            cell, n = host["cell"][axis], host["cells"][axis]
            c0 = int(np.clip(np.floor((lo[q, axis] - host["bounds"][axis]) / cell), 0, n - 1))
            c1 = int(np.clip(np.floor((hi[q, axis] - host["bounds"][axis]) / cell), 0, n - 1))
            base = axis * (host["max_cells"] + 1)
            counts.append(host["offsets"][base + c1 + 1] - host["offsets"][base + c0])
        if min(counts) > 0:
            assert walked[q] == min(counts)
