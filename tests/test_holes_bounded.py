"""Hole filling does bounded work: a loop whose quality triangulation would be unbounded (a
sliver through a vertex far from the others) is refused quickly with a clear reason."""

import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from meshrepair.errors import MeshRepairError
from meshrepair.holes._triangle import MIN_ANGLE, STEINER_MIN, steiner_cap, triangulate_capped

SPIKED_INPAINT = textwrap.dedent("""
    import time
    import numpy as np
    import trimesh
    import meshrepair as mr

    m = trimesh.creation.icosphere(3)
    V = np.asarray(m.vertices).copy()
    F = np.asarray(m.faces)
    V[0] += (1e6, 0.0, 0.0)  # one vertex moved far away
    ring = np.unique(F[(F == 0).any(axis=1)].ravel())
    t = time.perf_counter()
    r = mr.inpaint(V, F, [int(ring[ring != 0][0])])  # the hole's loop passes through vertex 0
    print(f"{time.perf_counter() - t:.3f}")
    for h in r.holes:
        print(h.status, "|", h.reason)
""")


def test_inpaint_next_to_a_far_vertex_returns_quickly():
    # the loop of the region's hole runs through the far vertex: its minimum-weight triangulation
    # is a 1e6-long sliver whose quality mesh Triangle refined for hours
    t = time.perf_counter()
    try:
        out = subprocess.run([sys.executable, "-c", SPIKED_INPAINT], capture_output=True,
                             text=True, timeout=120)
    except subprocess.TimeoutExpired:
        pytest.fail("inpaint next to a far vertex did not return within 120 s")
    assert out.returncode == 0, out.stderr[-2000:]
    lines = out.stdout.strip().splitlines()
    assert float(lines[0]) < 30.0, f"inpaint took {lines[0]} s ({time.perf_counter() - t:.1f} s)"
    status, reason = lines[1].split(" | ")
    # refused with its reason (the developed layout gives up at its Steiner bound; the capped
    # mean-value layout's patch is then refused or, past its own cap, the loop is)
    assert status == "skipped" and len(reason) > 20


def _fan(far, n=5):
    """A loop of ``n`` short edges (radius 0.3) closed through one vertex at distance ``far``,
    with the chords from that vertex as constraints: the coarse triangulation of such a loop
    with its folds kept as edges (liepa_refine), a fan of slivers of small angles."""
    a = np.linspace(0.0, 1.2, n)
    Q = np.r_[[[0.9 * far, 0.4 * far]], 0.3 * np.c_[np.cos(a), -np.sin(a)]]
    k = len(Q)
    segs = np.r_[np.c_[np.arange(k), (np.arange(k) + 1) % k],
                 np.c_[np.zeros(k - 3, np.int64), np.arange(2, k - 1)]]
    return Q, segs


def test_sliver_polygon_is_refused_after_bounded_work():
    Q, segs = _fan(1e6)
    k = len(Q)
    h = float(np.linalg.norm(Q - np.roll(Q, -1, axis=0), axis=1).mean())  # hole filling's default
    amax = 1.6 * np.sqrt(3.0) / 4.0 * h * h
    cap = steiner_cap(Q, k, amax)
    assert cap < 2 * STEINER_MIN
    t = time.perf_counter()
    with pytest.raises(MeshRepairError, match="long thin polygon"):
        triangulate_capped({"vertices": Q, "segments": segs},
                           f"pYQq{MIN_ANGLE:g}", cap, max_area=amax)
    assert time.perf_counter() - t < 20.0


def test_cap_leaves_room_for_a_regular_polygon():
    # a regular 60-gon of unit radius at an area bound giving about 2000 triangles: Triangle
    # adds about 1000 points, far below the cap
    k = 60
    a = 2 * np.pi * np.arange(k) / k
    Q = np.c_[np.cos(a), np.sin(a)]
    segs = np.c_[np.arange(k), (np.arange(k) + 1) % k]
    amax = np.pi / 2000
    cap = steiner_cap(Q, k, amax)
    out = triangulate_capped({"vertices": Q, "segments": segs},
                             f"pYQq{MIN_ANGLE:g}", cap, max_area=amax)
    added = len(out["vertices"]) - k
    assert 500 < added < cap / 10
    assert cap >= STEINER_MIN
