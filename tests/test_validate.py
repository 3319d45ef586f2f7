"""Tests of meshrepair.mesh.validate.check_mesh: every refusal, every warning, the report."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from meshrepair.errors import MeshRepairError
from meshrepair.mesh.validate import MeshReport, check_mesh

from .conftest import SHARED, needs_meshes

MESHES = SHARED


def tetra():
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]])
    return V, F


def grid(n=6, hole=False):
    """(n x n) vertex grid in the plane, 2 triangles per cell, consistently oriented."""
    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float), indexing="ij")
    V = np.c_[x.ravel(), y.ravel(), np.zeros(n * n)]
    idx = np.arange(n * n).reshape(n, n)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    F = np.r_[np.c_[a, b, c], np.c_[a, c, d]]
    if hole:  # remove the two triangles of an interior cell
        cell = (n - 1) * 2 + 2
        F = np.delete(F, [cell, cell + (n - 1) ** 2], axis=0)
    return V, F


# ------------------------------------------------------------------------------------------------
# accepted meshes and the report
# ------------------------------------------------------------------------------------------------


def test_closed_tetra_report():
    V, F = tetra()
    r = check_mesh(V, F)
    assert isinstance(r, MeshReport)
    assert (r.n_vertices, r.n_faces, r.n_edges) == (4, 4, 6)
    assert r.n_components == 1 and r.n_boundary_loops == 0 and r.n_boundary_edges == 0
    assert r.is_closed
    assert r.n_duplicate_vertices == r.n_unreferenced == r.n_pinched_vertices == 0
    assert r.mean_edge_length == pytest.approx((3 * 1 + 3 * np.sqrt(2)) / 6)
    s = r.summary()
    assert "4 vertices, 4 faces, 6 edges, 1 component, closed" in s
    assert "warnings" not in s


def test_open_grid_with_hole():
    V, F = grid(6, hole=True)
    r = check_mesh(V, F, name="grid")
    assert not r.is_closed
    assert r.n_boundary_loops == 2  # outer border + the hole
    assert r.n_boundary_edges == 20 + 4
    assert r.n_faces == 48
    assert "grid: " in r.summary() and "2 boundary loops" in r.summary()


def test_integral_float_faces_and_int_vertices_accepted():
    V, F = tetra()
    r = check_mesh(V.astype(np.int32), F.astype(np.float64))
    assert r.n_faces == 4


def test_inputs_not_modified():
    V, F = grid(5)
    V0, F0 = V.copy(), F.copy()
    check_mesh(V, F)
    np.testing.assert_array_equal(V, V0)
    np.testing.assert_array_equal(F, F0)


# ------------------------------------------------------------------------------------------------
# refusals
# ------------------------------------------------------------------------------------------------


def test_quads_refused():
    V, _ = grid(3)
    Q = np.array([[0, 3, 4, 1], [1, 4, 5, 2]])
    with pytest.raises(MeshRepairError, match=r"expected F of shape \(nF, 3\).*got shape \(2, 4\)"
                       r".*quads: triangulate"):
        check_mesh(V, Q, name="quadmesh")
    with pytest.raises(MeshRepairError, match=r"^quadmesh: "):
        check_mesh(V, Q, name="quadmesh")


def test_point_cloud_refused():
    V = np.random.default_rng(0).random((10, 3))
    with pytest.raises(MeshRepairError, match=r"empty mesh: no faces.*point cloud"):
        check_mesh(V, np.empty((0, 3), dtype=int))
    with pytest.raises(MeshRepairError, match=r"point cloud"):
        check_mesh(V, None)


def test_bad_vertex_shape_refused():
    _, F = tetra()
    with pytest.raises(MeshRepairError, match=r"expected V of shape \(nV, 3\).*got shape \(4, 2\)"
                       r".*zero z column"):
        check_mesh(np.zeros((4, 2)), F)
    with pytest.raises(MeshRepairError, match=r"got shape \(12,\).*reshape\(-1, 3\)"):
        check_mesh(np.zeros(12), F)


def test_empty_vertices_refused():
    with pytest.raises(MeshRepairError, match="empty mesh: no vertices"):
        check_mesh(np.zeros((0, 3)), np.array([[0, 1, 2]]))


def test_non_integer_faces_refused():
    V, F = tetra()
    Ff = F.astype(float)
    Ff[2, 1] = 1.5
    with pytest.raises(MeshRepairError,
                       match=r"integer vertex indices.*1 entries.*first rows: \[2\]"):
        check_mesh(V, Ff)
    Ff[2, 1] = np.nan
    with pytest.raises(MeshRepairError, match="non-integer or non-finite"):
        check_mesh(V, Ff)
    with pytest.raises(MeshRepairError, match="dtype bool"):
        check_mesh(V, F.astype(bool))
    with pytest.raises(MeshRepairError, match="real numeric"):
        check_mesh(V.astype(str), F)


def test_nan_vertices_refused():
    V, F = grid(4)
    V[5, 2] = np.nan
    V[9, 0] = -np.inf
    with pytest.raises(MeshRepairError, match=r"2 of 16 vertices have NaN or infinite coordinates "
                       r"\(first vertices: \[5, 9\]\)"):
        check_mesh(V, F)


def test_out_of_range_indices_refused():
    V, F = tetra()
    F2 = F.copy()
    F2[1, 2] = 7
    with pytest.raises(MeshRepairError, match=r"out of range: valid range is \[0, 3\].*got indices "
                       r"in \[0, 7\].*first faces: \[1\]"):
        check_mesh(V, F2)
    F2[1, 2] = -1
    with pytest.raises(MeshRepairError, match=r"got indices in \[-1, 3\].*must not be negative"):
        check_mesh(V, F2)


def test_repeated_indices_refused():
    V, F = grid(4)
    F = F.copy()
    F[3] = [3, 3, 5]
    F[7] = [1, 2, 1]
    with pytest.raises(MeshRepairError, match=r"2 faces have repeated vertex indices \(first "
                       r"faces: \[3, 7\], e\.g\. face 3 = \[3, 3, 5\]\); remove them"):
        check_mesh(V, F)


def test_zero_area_faces_refused_or_warned(caplog):
    V, F = grid(4)
    V2 = V.copy()
    V2[15] = V2[14]  # coincident corners (distinct indices): face [10, 14, 15] has zero area
    with pytest.raises(MeshRepairError, match=r"zero-area \(degenerate\) faces.*first faces: "
                       r"\[.*\].*remove or collapse them"):
        check_mesh(V2, F)
    n_expected = int(np.sum([np.isin(15, f) and np.isin(14, f) for f in F]))
    with caplog.at_level(logging.WARNING, logger="meshrepair.mesh.validate"):
        r = check_mesh(V2, F, allow_degenerate=True)
    assert r.n_degenerate_faces == n_expected == 1
    assert "zero-area" in caplog.text and "allow_degenerate=True" in caplog.text
    assert "1 zero-area faces" in r.summary()


def test_collinear_face_detected_scale_free():
    for scale in (1e-9, 1.0, 1e9):
        V = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 1, 0]], dtype=float) * scale
        F = np.array([[0, 1, 3], [1, 2, 3], [0, 2, 1]])  # last face: three collinear corners
        with pytest.raises(MeshRepairError, match=r"1 zero-area .*first faces: \[2\]"):
            check_mesh(V, F)
        V[1, 1] = -1e-3 * scale  # no longer collinear: accepted at every scale
        assert check_mesh(V, F).n_faces == 3


def test_non_manifold_edge_refused():
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]])
    F = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])  # edge (0, 1) in three faces
    with pytest.raises(MeshRepairError, match=r"1 non-manifold edges \(shared by more than 2 faces;"
                       r" first: \(0, 1\) in 3 faces\); split or clean"):
        check_mesh(V, F)


def test_inconsistent_orientation_refused():
    V, F = grid(4)
    F = F.copy()
    F[4] = F[4, ::-1]
    with pytest.raises(MeshRepairError, match=r"inconsistent face orientation: 3 interior edges.*"
                       r"same direction.*faces 4 and.*fix_winding.*fix_normals"):
        check_mesh(V, F)


# ------------------------------------------------------------------------------------------------
# warnings and counts
# ------------------------------------------------------------------------------------------------


def test_duplicate_vertices_warned_and_kept(caplog):
    V, F = tetra()
    V = np.r_[V, V[[1]], [[-0.0, 0.0, 0.0]]]  # 4 duplicates 1, 5 duplicates 0 (-0.0 == 0.0)
    F = np.r_[F, [[4, 5, 2]]]
    F[0] = [0, 2, 1]
    with caplog.at_level(logging.WARNING, logger="meshrepair.mesh.validate"):
        r = check_mesh(V, F)
    assert r.n_duplicate_vertices == 2
    assert r.n_vertices == 6
    assert "2 vertices duplicate the position" in caplog.text and "[4, 5]" in caplog.text


def test_unreferenced_vertices_warned(caplog):
    V, F = tetra()
    V = np.r_[V, [[5.0, 5, 5], [6, 6, 6]]]
    with caplog.at_level(logging.WARNING, logger="meshrepair.mesh.validate"):
        r = check_mesh(V, F)
    assert r.n_unreferenced == 2
    assert r.n_components == 1  # unreferenced vertices are not components
    assert "2 unreferenced vertices" in caplog.text and "[4, 5]" in caplog.text


def test_denoise_keeps_unreferenced_vertices_bit_for_bit():
    """The validation's promise: a vertex no face uses comes back where it was."""
    import trimesh

    import meshrepair as mr

    s = trimesh.creation.icosphere(2)
    V = s.vertices + np.random.default_rng(0).normal(size=s.vertices.shape) * 0.01
    V = np.r_[V, [[100.0, 100.0, 100.0], [-3.0, 0.5, 7.0]]]
    r = mr.denoise(V, s.faces)
    assert np.array_equal(r.V[-2:], V[-2:])
    assert np.abs(r.V[:-2] - V[:-2]).max() > 0  # the mesh itself was denoised
    p = mr.denoise(V, s.faces, plan=mr.plan_denoise(V, s.faces))
    assert np.array_equal(p.V[-2:], V[-2:])


@pytest.mark.parametrize("F", [[[0, 1, 2]], [[0, 1, 2], [0, 2, 3]]])
def test_denoise_of_a_few_faces_raises_no_numpy_warning(F):
    """One triangle or a square: no vertex lies far enough inside for the noise's profile; the
    reading is white, with no 'mean of empty slice' from numpy."""
    import warnings

    import meshrepair as mr

    V = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])[: np.max(F) + 1]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = mr.denoise(V, np.array(F))
    assert np.isfinite(r.V).all() and r.V.shape == V.shape


@pytest.mark.parametrize("k, msg", [(1e60, "coordinates up to"), (1e-60, "span only")])
def test_coordinates_outside_the_range_are_refused_with_the_factor(k, msg):
    V, F = tetra()
    with pytest.raises(MeshRepairError, match=msg) as e:
        check_mesh(V * k, F)
    assert "rescale the mesh" in str(e.value)
    check_mesh(V * 1e45, F)  # inside the range: accepted
    check_mesh(V * 1e-45, F)


def test_pinched_boundary_vertex_warned(caplog):
    # bow tie: two triangles touching at vertex 0
    V = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [-1, 0, 0], [-1, -1, 0]])
    F = np.array([[0, 1, 2], [0, 3, 4]])
    with caplog.at_level(logging.WARNING, logger="meshrepair.mesh.validate"):
        r = check_mesh(V, F)
    assert r.n_pinched_vertices == 1
    assert r.n_boundary_loops == 1  # the two loops share vertex 0
    assert "1 non-manifold (pinched) vertices" in caplog.text and "[0]" in caplog.text


def test_pinched_interior_vertex_two_closed_fans(caplog):
    # two tetrahedra sharing only vertex 0: no boundary, vertex 0 has two closed fans
    V1, F1 = tetra()
    V2 = -V1[1:] - 0.5
    V = np.r_[V1, V2]
    F2 = F1.copy()
    F2[F1 > 0] += 3
    F2 = F2[:, ::-1]  # mirrored copy: flip to keep outward orientation consistent
    F = np.r_[F1, F2]
    with caplog.at_level(logging.WARNING, logger="meshrepair.mesh.validate"):
        r = check_mesh(V, F)
    assert r.is_closed
    assert r.n_pinched_vertices == 1
    assert r.n_components == 1


def test_components_counted_and_logged(caplog):
    V, F = tetra()
    V2 = np.r_[V, V + 10]
    F2 = np.r_[F, F + 4]
    with caplog.at_level(logging.INFO, logger="meshrepair.mesh.validate"):
        r = check_mesh(V2, F2)
    assert r.n_components == 2
    assert "2 connected components" in caplog.text
    assert r.n_pinched_vertices == 0 and r.n_duplicate_vertices == 0


# ------------------------------------------------------------------------------------------------
# real meshes and size
# ------------------------------------------------------------------------------------------------


@needs_meshes
def test_real_meshes_match_manifest(caplog):
    from meshrepair.io import read_mesh

    m = read_mesh(MESHES / "kinect_pyramid.ply")
    with caplog.at_level(logging.WARNING, logger="meshrepair.mesh.validate"):
        r = check_mesh(m.V, m.F, name="kinect_pyramid")
    assert (r.n_vertices, r.n_faces) == (6627, 12559)
    assert r.n_boundary_loops == 14 and r.n_pinched_vertices == 8  # MANIFEST.md
    assert r.n_components == 1
    f = read_mesh(MESHES / "fandisk.ply")
    rf = check_mesh(f.V, f.F)
    assert rf.is_closed and rf.n_edges == 19419
    assert rf.mean_edge_length == pytest.approx(0.108366, abs=1e-6)
    assert rf.n_vertices - rf.n_edges + rf.n_faces == 2  # Euler characteristic, MANIFEST.md


def test_large_grid_is_fast_enough():
    import time

    V, F = grid(300)  # 90k vertices, 178k faces
    t = time.perf_counter()
    r = check_mesh(V, F)
    assert time.perf_counter() - t < 5.0
    assert r.n_faces == 2 * 299 * 299 and r.n_boundary_loops == 1
