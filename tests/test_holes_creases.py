"""Crease continuation through holes (issue 13): sharp-edge chains ending on a loop are paired
across the hole (or meet at a corner), routed through the patch and rebuilt sharp."""

from __future__ import annotations

import numpy as np
import pytest

from meshrepair.fill import _edge_ids, fill_holes, inpaint
from meshrepair.holes import find_holes
from meshrepair.holes.creases import SharpGraph, crease_ends, route_creases
from meshrepair.mesh.geometry import dihedral_angles, face_normals
from meshrepair.mesh.topology import edge_topology
from meshrepair.mesh.validate import check_mesh


def _merged(V, F):
    import trimesh

    m = trimesh.Trimesh(V, F, process=False)
    m.merge_vertices()
    return np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)


@pytest.fixture(scope="module")
def box():
    import trimesh

    b = trimesh.creation.box((2.0, 2.0, 2.0))
    return _merged(*trimesh.remesh.subdivide_to_size(b.vertices, b.faces, 0.1))


@pytest.fixture(scope="module")
def cylinder():
    import trimesh

    c = trimesh.creation.cylinder(radius=1.0, height=2.0, sections=64)
    return _merged(*trimesh.remesh.subdivide_to_size(c.vertices, c.faces, 0.1))


def _crease_dihedrals(res):
    topo = edge_topology(res.F, len(res.V))
    ang = dihedral_angles(face_normals(res.V, res.F), topo)
    ids = np.concatenate([_edge_ids(topo, h.sharp_edges, len(res.V)) for h in res.holes])
    return ang, ids, topo


def _normal_deviation_box(res):
    """Angle of every patch face normal to the nearest box axis (the truth is axis-aligned)."""
    N = face_normals(res.V, res.F)[res.new_faces]
    return np.degrees(np.arccos(np.clip(np.abs(N).max(axis=1), -1.0, 1.0)))


@pytest.mark.parametrize("center, radius, n_creases, kinds", [
    ((1.0, 0.0, 1.0), 0.35, 1, {"pair"}),          # across an edge
    ((1.0, 0.3, 1.0), 0.6, 1, {"pair"}),           # across an edge, close to a corner
    ((1.0, 1.0, 1.0), 0.4, 3, {"corner"}),         # centred on a corner
    ((1.0, 0.5, 0.6), 0.7, 3, {"corner"}),         # a corner off-centre in a large hole
])
def test_box_edge_and_corner_rebuilt_sharp(box, center, radius, n_creases, kinds):
    V, F = box
    res = inpaint(V, F, ("sphere", center, radius))
    assert res.n_filled == 1, res.summary()
    h = res.holes[0]
    assert h.n_creases == n_creases and f"{n_creases} crease" in h.reason
    ang, ids, _ = _crease_dihedrals(res)
    assert len(ids) >= 3
    assert np.abs(ang[ids] - 90.0).max() < 5.0  # restored dihedral within 5° of the truth
    assert _normal_deviation_box(res).max() < 1.0  # both sides stay planar
    check_mesh(res.V, res.F)
    if kinds == {"corner"}:  # the corner vertex is rebuilt at the box corner
        d = np.linalg.norm(res.V[res.new_vertices] - np.sign(center), axis=1).min()
        # (measured 3.3e-6 off-centre: the solve's sub-1e-6 move of the route's corner, then
        # the move along the loop's normal onto the box's planes, holes.envelope)
        assert d < 1e-5
    # without crease continuation the edge is smoothed away
    smooth = inpaint(V, F, ("sphere", center, radius), creases=False)
    assert _normal_deviation_box(smooth).mean() > 5.0


def test_fill_holes_continues_a_crease_too(box):
    V, F = box
    cen = V[F].mean(axis=1)
    keep = np.linalg.norm(cen - [1.0, -0.2, 1.0], axis=1) > 0.3
    Fk = F[keep]
    res = fill_holes(V, Fk)
    assert res.n_filled == 1 and res.holes[0].n_creases == 1
    ang, ids, _ = _crease_dihedrals(res)
    assert np.abs(ang[ids] - 90.0).max() < 5.0


def test_cylinder_rim_crease_followed_round(cylinder):
    V, F = cylinder
    res = inpaint(V, F, ("sphere", (1.0, 0.0, 1.0), 0.4))
    h = res.holes[0]
    assert h.n_creases == 1
    ang, ids, _ = _crease_dihedrals(res)
    # the rim is a circle: the routed crease follows it (Hermite curve) and stays on it
    Pc = res.V[np.unique(h.sharp_edges)]
    assert np.abs(np.hypot(Pc[:, 0], Pc[:, 1]) - 1.0).max() < 0.01
    assert np.abs(Pc[:, 2] - 1.0).max() < 1e-4
    assert abs(float(np.mean(ang[ids])) - 90.0) < 5.0  # restored dihedral within 5°


def test_crease_pairing_rules():
    """Ends pair only when aligned with the chord, of the same convexity and similar angle."""
    import trimesh

    b = trimesh.creation.box((2.0, 2.0, 2.0))
    V, F = _merged(*trimesh.remesh.subdivide_to_size(b.vertices, b.faces, 0.1))
    cen = V[F].mean(axis=1)
    Fk = F[np.linalg.norm(cen - [1.0, 0.0, 1.0], axis=1) > 0.3]
    hole = find_holes(V, Fk)[0]
    G = SharpGraph(V, Fk, 30.0)
    ends = crease_ends(G, hole.vertices)
    assert len(ends) == 2 and all(e.convex for e in ends)
    assert all(abs(e.angle - 90.0) < 1e-6 for e in ends)
    r = route_creases(V, hole.vertices, ends)
    assert r is not None and r.kinds == ["pair"]
    # the straight edge stays straight: the Hermite curve is the chord
    t = np.linspace(0, 1, 7)
    pts = r.evaluate(0, t)
    assert np.allclose(pts[:, 0], 1.0) and np.allclose(pts[:, 2], 1.0)
    # opposite convexity: no pair
    ends[1].convex = False
    assert route_creases(V, hole.vertices, ends) is None
    ends[1].convex = True
    ends[1].angle = 40.0
    assert route_creases(V, hole.vertices, ends) is None


def test_smooth_hole_gets_no_crease():
    import trimesh

    s = trimesh.creation.icosphere(4)
    V, F = np.asarray(s.vertices), np.asarray(s.faces, np.int64)
    res = inpaint(V, F, ("sphere", (0.0, 0.0, 1.0), 0.3))
    assert res.n_filled == 1 and res.holes[0].n_creases == 0


# ------------------------------------------------------------------------------------------------
# curvature continuity: a sphere's hole is refilled by the sphere
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("z_cut, tol", [(0.9, 0.005), (0.8, 0.005), (0.6, 0.03)])
def test_sphere_cap_refilled_by_the_sphere(z_cut, tol):
    """Holes of cap height 0.1, 0.2 and 0.4 radii in a unit sphere: the patch vertices lie within
    ``tol`` of the sphere (radial error; the plain thin plate was off by 0.0035, 0.014 and 0.059,
    the flat membrane by 0.11, 0.21 and 0.41)."""
    import trimesh

    s = trimesh.creation.icosphere(5)
    V, F = np.asarray(s.vertices), np.asarray(s.faces, np.int64)
    keep = ~(V[F][:, :, 2] > z_cut).any(axis=1)
    used = np.unique(F[keep])
    m = -np.ones(len(V), np.int64)
    m[used] = np.arange(len(used))
    Vc, Fc = V[used], m[F[keep]]
    res = fill_holes(Vc, Fc)
    assert res.n_filled == 1
    err = np.abs(np.linalg.norm(res.V[res.new_vertices], axis=1) - 1.0)
    assert err.max() < tol, err.max()
    plain = fill_holes(Vc, Fc, refine=False, curvature=False, triharmonic=False)
    err_plain = np.abs(np.linalg.norm(plain.V[plain.new_vertices], axis=1) - 1.0)
    assert err.max() < 0.5 * err_plain.max()


def test_t_junction_route():
    """A leftover crease whose line meets a paired crease ends on it (the pair is split)."""
    from meshrepair.holes.creases import CreaseEnd

    V = np.array([[-1.0, 0, 0], [0, -1.0, 0], [1.0, 0, 0], [0, 1.0, 0]])
    loop = np.arange(4)
    ends = [CreaseEnd(pos=0, vertex=0, direction=np.array([1.0, 0, 0]), angle=90.0, convex=True),
            CreaseEnd(pos=2, vertex=2, direction=np.array([-1.0, 0, 0]), angle=90.0,
                      convex=True),
            CreaseEnd(pos=1, vertex=1, direction=np.array([0, 1.0, 0]), angle=60.0,
                      convex=False)]
    r = route_creases(V, loop, ends)
    assert r.kinds == ["junction"] * 3 and len(r.points) == 1
    assert np.allclose(r.points[0], 0.0, atol=0.02)
    assert sorted(r.segments[:, 0].tolist()) == [0, 1, 2] and (r.segments[:, 1] == 4).all()
    for j in range(3):  # every sub-curve runs from its loop end to the junction
        a, b = r.evaluate(j, np.array([0.0, 1.0]))
        assert np.allclose(a, V[r.segments[j, 0]]) and np.allclose(b, r.points[0])


def test_l_prism_concave_crease_and_mixed_corner():
    """An L-shaped prism: a hole across its concave crease, and one on the corner where that
    concave crease meets two convex ones."""
    import triangle
    import trimesh

    # profile in the xz plane, extruded along y over [0, 2]; caps by Triangle, sides as quads
    prof = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], float)
    k = len(prof)
    t = triangle.triangulate({"vertices": prof, "segments": np.c_[np.arange(k),
                                                                  (np.arange(k) + 1) % k]}, "p")
    T = np.asarray(t["triangles"])
    V0 = np.c_[prof[:, 0], np.zeros(k), prof[:, 1]]
    V1 = V0 + [0, 2.0, 0]
    Vm = np.r_[V0, V1]
    caps = np.r_[T, T[:, ::-1] + k]
    sides = np.concatenate([[[i, (i + 1) % k, k + (i + 1) % k], [i, k + (i + 1) % k, k + i]]
                            for i in range(k)])
    Fm = np.r_[caps, sides]
    mesh = trimesh.Trimesh(Vm, Fm, process=True)
    trimesh.repair.fix_normals(mesh)
    V, F = _merged(*trimesh.remesh.subdivide_to_size(mesh.vertices, mesh.faces, 0.1))
    for center, n in (((1.0, 1.0, 1.0), 1), ((1.0, 0.0, 1.0), 3)):
        res = inpaint(V, F, ("sphere", center, 0.35))
        assert res.n_filled == 1 and res.holes[0].n_creases == n, res.summary()
        ang, ids, _ = _crease_dihedrals(res)
        assert np.abs(ang[ids] - 90.0).max() < 5.0
        assert _normal_deviation_box(res).max() < 1.0


def test_pair_tilt_past_the_bound():
    """Ends within ``PAIR_MAX_TILT`` of the hole's plane pair; one end tilted past it pairs when
    the mean direction is within it and the route stays inside the loop seen through the plane;
    two ends tilted the same way (a fold diving into a flat cut) do not pair."""
    from meshrepair.holes.creases import PAIR_MAX_TILT, CreaseEnd

    t = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    V = np.c_[-np.cos(t), 0.05 * np.sin(t), np.zeros_like(t)]  # a narrow planar loop along x
    loop = np.arange(len(t))

    def pair(tilt_a, tilt_b, yaw=0.0):
        a, b, c = np.radians(tilt_a), np.radians(tilt_b), np.radians(yaw)
        da = np.array([np.cos(a) * np.cos(c), np.cos(a) * np.sin(c), np.sin(a)])
        db = np.array([-np.cos(b) * np.cos(c), np.cos(b) * np.sin(c), np.sin(b)])
        ends = [CreaseEnd(pos=0, vertex=0, direction=da, angle=90.0, convex=True),
                CreaseEnd(pos=12, vertex=12, direction=db, angle=90.0, convex=True)]
        r = route_creases(V, loop, ends)
        return r is not None and r.kinds == ["pair"]

    assert PAIR_MAX_TILT < 33.0
    assert pair(20.0, 20.0)
    assert pair(33.0, -33.0)  # both ends past the bound, the route on the plane
    assert pair(33.0, 5.0)
    assert not pair(33.0, 33.0)  # both ends leaving the plane the same way
    # the route bulging sideways over the loop (both ends turned 12° to +y)
    assert pair(20.0, 20.0, yaw=12.0)  # within the bound: the route is not read
    assert not pair(33.0, 5.0, yaw=12.0)
