import numpy as np
import pytest
import scipy.sparse as sp
import trimesh

from meshrepair.mesh.geometry import (
    dihedral_angles,
    edge_lengths,
    face_normals,
    face_normals_areas,
    mean_edge_length,
    sharp_edge_mask,
)
from meshrepair.mesh.operators import (
    apply_gradient,
    apply_gradient_transpose,
    edge_willmore_energy,
    gradient_operator,
    normal_system_matrix,
)
from meshrepair.mesh.topology import boundary_loops, edge_topology
from meshrepair.model.linear import block_pcg, direct_solve


def test_edge_topology_cube():
    m = trimesh.creation.box()
    t = edge_topology(m.faces)
    assert t.n_edges == 18 and t.interior.all()
    assert np.all(t.edge_faces[:, 0] < t.edge_faces[:, 1])
    # face_edges indexes the half-edge (F[k], F[k+1])
    e = t.edges[t.face_edges]
    f = np.sort(np.stack([m.faces, np.roll(m.faces, -1, 1)], 2), axis=2)
    assert np.array_equal(e, f)


def test_dihedral_and_sharp_mask_on_cube():
    m = trimesh.creation.box()
    t = edge_topology(m.faces)
    N = face_normals(np.asarray(m.vertices, float), m.faces)
    d = dihedral_angles(N, t)
    assert np.sum(np.isclose(d, 90)) == 12 and np.sum(np.isclose(d, 0, atol=1e-6)) == 6
    assert sharp_edge_mask(N, t, 30).sum() == 12


def test_gradient_operator_matches_definition_4(rng):
    m = trimesh.creation.icosphere(2)
    V = np.asarray(m.vertices) + 0.02 * rng.normal(size=m.vertices.shape)
    t = edge_topology(m.faces)
    D = gradient_operator(V, t)
    l = edge_lengths(V, t.edges)
    N = face_normals(V, m.faces)
    assert np.allclose(D @ N, apply_gradient(N, l, t))
    X = rng.normal(size=(t.n_edges, 3))
    assert np.allclose(D.T @ X, apply_gradient_transpose(X, l, t))
    i = 5
    j, k = t.edge_faces[i]
    assert D[i, j] == pytest.approx(l[i]) and D[i, k] == pytest.approx(-l[i])  # j < k
    A = normal_system_matrix(l, t, 2.5)
    assert abs(A - (D.T @ D + 2.5 * sp.identity(t.n_faces))).max() < 1e-12


def test_normal_solvers_agree(rng):
    m = trimesh.creation.icosphere(3)
    V = np.asarray(m.vertices)
    t = edge_topology(m.faces)
    A = normal_system_matrix(edge_lengths(V, t.edges) / mean_edge_length(V, m.faces), t, 1.7)
    B = rng.normal(size=(t.n_faces, 3))
    X1, it = block_pcg(A, B, rtol=1e-10)
    X2 = direct_solve(A, B)
    assert it < 100
    assert np.abs(X1 - X2).max() < 1e-8


@pytest.mark.parametrize("subdiv,h_paper,e_paper", [(4, 0.1208, 0.1182), (6, 0.0308, 0.0075),
                                                    (8, 0.0076, 0.00047)])
def test_willmore_sphere_remark_1(subdiv, h_paper, e_paper):
    m = trimesh.creation.icosphere(subdivisions=subdiv - 1)
    V = np.asarray(m.vertices)
    h = mean_edge_length(V, m.faces)
    E = edge_willmore_energy(V, m.faces)
    # same order of magnitude as the paper, after accounting for the slightly different h
    assert 0.4 < E / (e_paper * (h / h_paper) ** 2) < 2.5


def test_willmore_decreases_like_h_squared():
    Es, hs = [], []
    for s in (2, 3, 4, 5):
        m = trimesh.creation.icosphere(subdivisions=s)
        Es.append(edge_willmore_energy(m.vertices, m.faces))
        hs.append(mean_edge_length(m.vertices, m.faces))
    slope = np.polyfit(np.log(hs), np.log(Es), 1)[0]
    assert 1.8 < slope < 2.2


def test_boundary_loops_follow_orientation():
    m = trimesh.creation.icosphere(2)
    F = np.asarray(m.faces)[3:]  # remove three faces: one or more holes
    loops = boundary_loops(F, len(m.vertices))
    assert sum(len(x) for x in loops) > 0
    he = set(map(tuple, np.stack([F, np.roll(F, -1, 1)], 2).reshape(-1, 2)))
    for loop in loops:
        for u, v in zip(loop, np.roll(loop, -1), strict=False):
            assert (u, v) in he  # boundary half-edges go along the faces


def test_face_areas():
    V = np.array([[0, 0, 0], [2, 0, 0], [0, 1, 0.0]])
    N, A = face_normals_areas(V, np.array([[0, 1, 2]]))
    assert A[0] == pytest.approx(1.0) and np.allclose(N[0], [0, 0, 1])
