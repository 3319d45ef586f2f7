import numpy as np
import pytest
import trimesh

from meshrepair.metrics import closest_points_on_triangles, distances, msae, vertex_error


def test_closest_point_matches_dense_sampling(rng):
    n = 200
    a, b, c = (rng.normal(size=(n, 3)) for _ in range(3))
    p = 2.0 * rng.normal(size=(n, 3))
    q = closest_points_on_triangles(p, a, b, c)
    d = np.linalg.norm(p - q, axis=1)
    u, v = np.meshgrid(np.linspace(0, 1, 201), np.linspace(0, 1, 201))
    keep = u + v <= 1
    u, v = u[keep], v[keep]
    for i in range(n):
        pts = a[i] + u[:, None] * (b[i] - a[i]) + v[:, None] * (c[i] - a[i])
        dense = np.linalg.norm(pts - p[i], axis=1).min()
        assert d[i] <= dense + 1e-12
        assert dense - d[i] < 2e-2 * max(np.linalg.norm(b[i] - a[i]), 1.0)


def test_msae_and_ev_analytic():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]])
    F = np.array([[0, 1, 2]])
    R = np.array([[1, 0, 0], [0, np.cos(0.1), -np.sin(0.1)], [0, np.sin(0.1), np.cos(0.1)]])
    assert msae(V @ R.T, V, F) == pytest.approx(np.degrees(0.1) ** 2)
    assert vertex_error(V + [0, 0, 1], V) == pytest.approx(np.sqrt(3) / 3)


def test_distances_sphere_offset():
    m = trimesh.creation.icosphere(4)
    V, F = np.asarray(m.vertices), np.asarray(m.faces)
    d = distances(1.01 * V, F, V, F)
    assert d["mean"] == pytest.approx(0.01, rel=0.1) and d["hausdorff"] < 0.012


def test_mean_angle_error_of_a_rotated_plane_is_the_rotation_angle():
    from meshrepair.metrics import mean_angle_error

    from .conftest import grid

    V, F = grid(6)
    th = np.radians(7.0)
    R = np.array([[1, 0, 0], [0, np.cos(th), -np.sin(th)], [0, np.sin(th), np.cos(th)]])
    W = V @ R.T
    assert mean_angle_error(W, V, F) == pytest.approx(7.0, abs=1e-9)
    assert mean_angle_error(W, V, F, degrees=False) == pytest.approx(th, abs=1e-12)
    assert msae(W, V, F) == pytest.approx(49.0, abs=1e-7)
    assert mean_angle_error(V, V, F) == pytest.approx(0.0, abs=1e-6)


def test_min_face_angles_analytic():
    from meshrepair.metrics import min_face_angles

    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, np.sqrt(3) / 2, 0], [0, 1, 0.0],
                  [2, 0, 0], [2, 2 * np.tan(np.radians(3)), 0], [5, 5, 5]])
    F = np.array([[0, 1, 2], [0, 1, 3], [0, 4, 5], [0, 0, 6]])
    a = min_face_angles(V, F)
    assert a[:3] == pytest.approx([60.0, 45.0, 3.0])
    assert a[3] == 0.0  # a zero-length edge: degenerate
    assert min_face_angles(V, F, degrees=False)[1] == pytest.approx(np.pi / 4)
    # invariant to rotation, scale and to the vertex order within a face
    R = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))[0]
    assert min_face_angles(3.0 * V @ R.T, F[:, [2, 0, 1]]) == pytest.approx(a)


def test_msae_faces_mask_is_the_msae_of_the_subset(rng):
    from meshrepair.errors import MeshRepairError

    V = rng.normal(size=(30, 3))
    F = rng.integers(0, 30, size=(40, 3))
    F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])]
    W = V + 0.05 * rng.normal(size=V.shape)
    mask = np.arange(len(F)) % 3 == 0
    assert msae(W, V, F, faces=mask) == pytest.approx(msae(W, V, F[mask]))
    assert msae(W, V, F, faces=np.ones(len(F), bool)) == msae(W, V, F)
    with pytest.raises(MeshRepairError, match="boolean mask"):
        msae(W, V, F, faces=np.flatnonzero(mask))
    with pytest.raises(MeshRepairError, match="no face"):
        msae(W, V, F, faces=np.zeros(len(F), bool))
