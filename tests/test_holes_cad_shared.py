"""CAD holes crossed by creases on shared meshes (issue 13): the cut-and-refill of
``benchmarks/holes.py --cases peers`` for the cases the exact / twin corner rules and the
triharmonic fairing brought under the target (patch normal deviation <= 5°)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from meshrepair.fill import fill_holes
from meshrepair.mesh.geometry import mean_edge_length

from .conftest import shared_mesh

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))


@pytest.mark.shared
@pytest.mark.parametrize("name, kind, r, max_normal, max_mean", [
    # measured 1.07°, 0.096e-3: median 0.02° over the 148 new faces, one face at the corner
    # matched across a crease by the nearest-centroid pairing (90°) is 0.61° of the mean
    ("fandisk", "corner", 4, 1.5, 0.3e-3),
    ("fandisk", "corner", 8, 5.0, 1.5e-3),   # measured 4.10°, 0.832e-3 (CGAL 18.8°, 4.08e-3)
    ("twelve", "crease", 8, 2.5, 1.0e-3),    # measured 1.15°, 0.339e-3 (CGAL 10.8°, 3.49e-3)
])
def test_cad_corner_holes_under_target(name, kind, r, max_normal, max_mean):
    import _holes_peers as hp
    from holes import cut_disc

    V, F = shared_mesh(f"{name}.ply")
    c = dict(hp.pick_centres(V, F))[kind]
    Vc, Fc, F_rm = cut_disc(V, F, c, r)
    res = fill_holes(Vc, Fc)
    assert res.n_filled == 1
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    new = hp.new_faces(Vc, Fc, res.V, res.F)
    m, _, nd, _, _, _ = hp.measure(V, F_rm, V, F, res.V, res.F, new, diag,
                                   mean_edge_length(V, F))
    assert nd <= max_normal, nd
    assert m <= max_mean, m


@pytest.mark.shared
@pytest.mark.parametrize("r, max_mean", [
    (8, 0.34e-3),    # measured 0.324e-3 (CGAL refine+fair 0.653e-3; thin plate 0.482e-3)
    (16, 0.82e-3),   # measured 0.780e-3 (CGAL 1.590e-3; triharmonic unscreened 0.880e-3)
])
def test_spot_smooth_hole_triharmonic(r, max_mean):
    """The smooth cut-and-refill of the peers table on spot (Loop-subdivided once, disc on the
    flank): the screened triharmonic patch is kept and is about half CGAL's distance."""
    import _holes_peers as hp
    import trimesh
    from holes import cut_disc

    V, F = shared_mesh("spot.ply")
    V, F = trimesh.remesh.subdivide_loop(V, F, iterations=1)
    V, F = np.asarray(V, float), np.asarray(F, np.int64)
    c = int(np.argmin(np.linalg.norm(V - np.array([0.47, 0.0, 0.2]), axis=1)))
    Vc, Fc, F_rm = cut_disc(V, F, c, r)
    res = fill_holes(Vc, Fc)
    assert "triharmonic" in res.holes[0].reason
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    new = hp.new_faces(Vc, Fc, res.V, res.F)
    m = hp.measure(V, F_rm, V, F, res.V, res.F, new, diag, mean_edge_length(V, F))[0]
    assert m <= max_mean, m


def _cut_refill(name, kind, r):
    import _holes_peers as hp
    from holes import cut_disc

    V, F = shared_mesh(f"{name}.ply")
    c = dict(hp.pick_centres(V, F))[kind]
    Vc, Fc, F_rm = cut_disc(V, F, c, r)
    res = fill_holes(Vc, Fc)
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    new = hp.new_faces(Vc, Fc, res.V, res.F)
    return res, hp.measure(V, F_rm, V, F, res.V, res.F, new, diag, mean_edge_length(V, F))


@pytest.mark.shared
@pytest.mark.parametrize("kind, max_mean, max_normal", [
    ("corner", 6.0e-3, 24.0),  # measured 5.695e-3, 22.2° (CGAL 6.142e-3, 19.8°; before 7.728)
    ("crease", 5.5e-3, 19.0),  # measured 5.039e-3, 17.1° (CGAL 5.768e-3, 18.3°; before 10.018)
])
def test_rocker_arm_r8_liepa_patch_below_cgal(kind, max_mean, max_normal):
    """rocker_arm r=8 (holes wrapping rounded rims; the seam rule encloses them by Liepa's
    triangulation): with the bounded cotangents of the Liepa patches' thin plate the patch is
    closer to the truth than CGAL refine-and-fair's."""
    res, (m, _, nd, _, _, _) = _cut_refill("rocker_arm", kind, 8)
    assert res.n_filled == 1 and res.holes[0].reason.startswith("liepa")
    assert m <= max_mean, m
    assert nd <= max_normal, nd


@pytest.mark.shared
def test_trim_star_kinked_crease_routed():
    """trim_star crease r=8: the crease that bends by 58° where it meets the loop is routed as
    a kinked pair; the restored crease error drops (measured 43.7° vs 55.7° unrouted)."""
    res, (m, _, nd, ce, _, _) = _cut_refill("trim_star", "crease", 8)
    assert res.n_filled == 1 and res.holes[0].n_creases == 1
    assert ce <= 48.0, ce
    assert m <= 4.5e-3, m  # measured 4.100e-3 (CGAL 7.246e-3)
