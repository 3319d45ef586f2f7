"""The synthetic-damage helpers used to build cut-and-repair cases (meshrepair.synthetic)."""

import numpy as np
import pytest
import trimesh

from meshrepair.errors import MeshRepairError
from meshrepair.mesh.topology import boundary_loops
from meshrepair.synthetic import (
    DAMAGES,
    damage_region,
    edge_graph_distances,
    geodesic_disc,
    random_rigid,
    symmetrize,
)

from .conftest import grid


def test_edge_graph_distance_along_a_grid_line_is_exact():
    V, F = grid(9)
    d = edge_graph_distances(V, F, 0)  # from the corner (0, 0, 0)
    on_axis = np.flatnonzero(V[:, 1] == 0)
    np.testing.assert_allclose(d[on_axis], V[on_axis, 0], atol=1e-12)
    # never shorter than the straight line
    assert np.all(d >= np.linalg.norm(V - V[0], axis=1) - 1e-12)


def test_geodesic_disc_contains_only_faces_within_the_radius():
    V, F = grid(15)
    c = 7 * 15 + 7
    faces, d = geodesic_disc(V, F, c, 3.0, return_distances=True)
    assert len(faces) > 0
    assert np.all(d[F[faces]] <= 3.0)
    assert len(boundary_loops(F[faces], len(V))) == 1


@pytest.mark.parametrize("kind", DAMAGES)
def test_damage_moves_the_interior_only(kind):
    m = trimesh.creation.icosphere(subdivisions=3)
    V, F = np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
    faces, d = geodesic_disc(V, F, 0, 0.5, return_distances=True)
    V0 = V.copy()
    Vd = damage_region(V, F, faces, d, 0.5, kind)
    np.testing.assert_array_equal(V, V0)  # input untouched
    b = boundary_loops(F[faces], len(V))[0]
    inner = np.setdiff1d(np.unique(F[faces]), b)
    outside = np.setdiff1d(np.arange(len(V)), inner)
    np.testing.assert_array_equal(Vd[outside], V[outside])
    assert np.abs(Vd[inner] - V[inner]).max() > 0


def test_unknown_damage_is_refused():
    V, F = grid(6)
    with pytest.raises(MeshRepairError, match="unknown damage"):
        damage_region(V, F, np.arange(4), np.zeros(len(V)), 1.0, "melt")


def test_random_rigid_is_a_proper_rotation():
    T = random_rigid(5, 3.0)
    R = T[:3, :3]
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0)
    np.testing.assert_array_equal(T[3], [0, 0, 0, 1])


def test_symmetrize_gives_a_mirror_symmetric_closed_mesh():
    m = trimesh.creation.icosphere(subdivisions=2)
    V = np.asarray(m.vertices, float) * [1.0, 0.8, 0.6] + [0.1, 0.0, 0.0]
    V[:, 0] += 0.2 * V[:, 1] ** 2  # not symmetric about x = const before
    Vs, Fs = symmetrize(V, np.asarray(m.faces, np.int64), axis=0)
    c = V.mean(axis=0)[0]
    M = Vs.copy()
    M[:, 0] = 2 * c - M[:, 0]
    # every mirrored vertex is a vertex
    dist = np.min(np.linalg.norm(M[:, None] - Vs[None], axis=2), axis=1)
    assert dist.max() < 1e-9
    assert trimesh.Trimesh(Vs, Fs, process=False).is_watertight
