"""The probe fields of meshrepair.mesh.probe are attached to the vertices, not to their indices:
a relabelled, rotated, translated or scaled mesh gets the same value on each vertex, and the
readings that use them (the noise scale, the band read, the risk level) are exactly equal on a
relabelled mesh."""

import numpy as np
import pytest
import trimesh

from meshrepair import add_noise
from meshrepair.denoise.corrwhite import band_read
from meshrepair.denoise.risk import normal_level, risk_curve
from meshrepair.denoise.scale import correlated_noise, noise_scale
from meshrepair.mesh.probe import canonical_order, probe_field
from meshrepair.mesh.topology import edge_topology, used_vertices


def _mesh():
    """A bumpy sphere without symmetry (no two vertices at the same distance from the centroid:
    vertices tied on that distance keep their index order, the one case the order depends on)."""
    m = trimesh.creation.icosphere(3)
    V = np.asarray(m.vertices, np.float64)
    V = V * (1.0 + 0.1 * np.sin(5 * V[:, :1]) + 0.01 * np.random.default_rng(7).random((len(V), 1)))
    return V, np.asarray(m.faces, np.int64)


def test_ties_keep_the_index_order():
    V = np.array([[1.0, 0, 0], [-1, 0, 0], [0, 2, 0], [0, -2, 0], [0, 0, 0.5]])
    assert canonical_order(V).tolist() == [4, 0, 1, 2, 3]


def _relabel(V, F, seed=3):
    p = np.random.default_rng(seed).permutation(len(V))
    inv = np.empty_like(p)
    inv[p] = np.arange(len(p))
    return V[p], inv[F][np.random.default_rng(seed + 1).permutation(len(F))], p


def test_order_sorts_by_distance_to_the_centroid():
    V, _ = _mesh()
    o = canonical_order(V)
    d = ((V - V.mean(axis=0)) ** 2).sum(axis=1)
    assert sorted(o.tolist()) == list(range(len(V)))
    assert np.all(np.diff(d[o]) >= -1e-12)


@pytest.mark.parametrize("kind", ["normal", "rademacher"])
def test_field_follows_the_vertices(kind):
    V, F = _mesh()
    Z = probe_field(V, 3, kind=kind)
    V2, _, p = _relabel(V, F)
    assert np.array_equal(probe_field(V2, 3, kind=kind), Z[p])
    R = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))[0]
    assert np.array_equal(probe_field(2.5 * V @ R.T + 7.0, 3, kind=kind), Z)
    if kind == "rademacher":
        assert set(np.unique(Z)) == {-1.0, 1.0}
    else:  # white: unit variance, no correlation between the columns
        assert abs(Z.std() - 1.0) < 0.05 and abs(np.corrcoef(Z.T)[0, 1]) < 0.1
    assert probe_field(V).shape == (len(V),)
    with pytest.raises(ValueError):
        probe_field(V, kind="uniform")


def test_readings_equal_on_a_relabelled_mesh():
    V, F = _mesh()
    Vn = correlated_noise(V, F, 0.3, 3, seed=1)
    Vn2, F2, p = _relabel(Vn, F)
    a, b = noise_scale(Vn, F, reference=V), noise_scale(Vn2, F2, reference=V[p])
    assert a.steps == b.steps and np.allclose(a.profile, b.profile, rtol=1e-12, atol=0)
    a, b = band_read(Vn, F, reference=V), band_read(Vn2, F2, reference=V[p])
    assert np.isclose(a.beta, b.beta, rtol=1e-12) and a.steps == b.steps
    Y = add_noise(V, F, 0.2, seed=2)
    Y2, F2, p = _relabel(Y, F)
    e, e2 = edge_topology(F, len(V)).edges, edge_topology(F2, len(V)).edges
    assert np.isclose(normal_level(Y, F, e), normal_level(Y2, F2, e2), rtol=1e-12)
    assert np.allclose(risk_curve(Y, F, e, 6), risk_curve(Y2, F2, e2, 6), rtol=1e-10)


def test_a_vertex_no_face_uses_changes_no_draw_and_no_reading():
    """A vertex no face uses is ranked last and read nowhere: every other vertex keeps its
    draw, and the noise scale reads the same profile."""
    V, F = _mesh()
    Vx = np.vstack([V, [[50.0, -3.0, 8.0]]])
    E = edge_topology(F, len(V)).edges
    Z, Zx = probe_field(V, 2), probe_field(Vx, 2, used=used_vertices(E, len(Vx)))
    assert np.array_equal(Zx[:-1], Z)
    Vn = correlated_noise(V, F, 0.3, 3, seed=1)
    Vnx = np.vstack([Vn, [[50.0, -3.0, 8.0]]])
    a, b = noise_scale(Vn, F), noise_scale(Vnx, F)
    assert np.array_equal(a.profile, b.profile) and a.steps == b.steps



def test_compact_keeps_the_used_vertices_in_order():
    """mesh.topology.compact: the used vertices in increasing order, the faces renumbered onto
    them (the same triangles), the unused ones gone."""
    from meshrepair.mesh.topology import compact

    V, F = _mesh()
    Vx = np.vstack([V[:5], [[9.0, 9.0, 9.0]], V[5:], [[-9.0, 0.0, 1.0]]])
    Fx = np.where(F >= 5, F + 1, F)
    idx, Vc, Fc = compact(Vx, Fx)
    assert np.array_equal(idx, np.r_[0:5, 6:len(Vx) - 1])
    assert np.array_equal(Vc, V) and np.array_equal(Fc, F) and np.array_equal(Vc[Fc], Vx[Fx])
    Vc[0] = 0.0
    assert not np.array_equal(Vx[0], Vc[0])  # a copy: the input is not touched
