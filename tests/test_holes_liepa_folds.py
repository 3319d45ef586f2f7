"""Liepa patches keep the folds of their coarse triangulation as edges without a cascade of tiny
triangles (:func:`meshrepair.holes.liepa_refine._refine_on_triangulation`): each fold is divided
into pieces of about the target length first, and Triangle may not split it further; the
``conforming`` variant (Triangle splits the folds for its angle bound) is the fill's retry."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from meshrepair.holes import liepa_refine as LR
from meshrepair.holes.detect import find_holes
from meshrepair.holes.liepa import min_weight_triangulation
from meshrepair.holes.liepa_layout import _unfold
from meshrepair.io import read_mesh
from meshrepair.mesh.topology import boundary_loops
from meshrepair.mesh.validate import check_mesh
from meshrepair.synthetic import cut_holes

DATA = Path(__file__).parent / "data"


def _loop(name: str, r: float, seed: int, index: int) -> np.ndarray:
    m = read_mesh(DATA / f"{name}.ply")
    Vc, Fc, _, _ = cut_holes(m.V, m.F, r, seed=seed)
    h = next(h for h in find_holes(Vc, Fc) if h.index == index)
    return Vc[h.vertices]


def _areas(X: np.ndarray, T: np.ndarray) -> np.ndarray:
    return 0.5 * np.linalg.norm(np.cross(X[T[:, 1]] - X[T[:, 0]], X[T[:, 2]] - X[T[:, 0]]),
                                axis=1)


@pytest.fixture
def full_search(monkeypatch):
    """Liepa patches from the minimum-weight triangulation over all triangles (not only the
    Delaunay facets of the loop), whose folds fan out of loop vertices on the loops below."""
    from functools import partial

    monkeypatch.setattr(LR, "min_weight_triangulation",
                        partial(min_weight_triangulation, search="all"))


# loops of cut holes on the bundled meshes whose coarse triangulation over all triangles folds
# in fans at a loop vertex (the conforming patch has tens to thousands of triangles below 0.1
# of the target)
CASES = [("fandisk", 6.0, 0, 2), ("trim_star", 4.0, 0, 1), ("spot", 6.0, 1, 0)]


@pytest.mark.parametrize("case", CASES, ids=lambda c: f"{c[0]}-r{c[1]:g}-s{c[2]}-h{c[3]}")
def test_divided_folds_stay_edges_without_tiny_triangles(case, full_search):
    P = _loop(*case)
    k = len(P)
    h = float(np.linalg.norm(P - np.roll(P, -1, axis=0), axis=1).mean())
    target = np.sqrt(3.0) / 4.0 * h * h
    Tc = LR._orient_patch(min_weight_triangulation(P, search="all"), k)
    folds = LR._creases(P, Tc, LR.LIEPA_CREASE)
    assert len(folds) > 0

    div = LR._enclose_liepa(P, h, None, None)
    conf = LR._enclose_liepa(P, h, None, None, conforming=True)
    assert div.n_folds == conf.n_folds == len(folds)
    for patch in (div, conf):
        X, T = patch.X, patch.T
        assert np.array_equal(X[:k], P)
        rep = check_mesh(X, T)
        assert rep.n_components == 1 and rep.n_boundary_loops == 1
        assert sorted(boundary_loops(T, len(X))[0].tolist()) == list(range(k))
    a_div, a_conf = _areas(div.X, div.T), _areas(conf.X, conf.T)
    # the same surface...
    assert a_div.sum() == pytest.approx(a_conf.sum(), rel=0.05)
    # ...meshed near the target size: few tiny triangles, far fewer than the conforming mesh
    assert (a_div < 0.1 * target).mean() < 0.1, (a_div < 0.1 * target).mean()
    assert (a_conf < 0.1 * target).sum() > 5 * max((a_div < 0.1 * target).sum(), 1)
    assert len(div.T) < 2.5 * a_div.sum() / target

    # every fold is a chain of patch edges along the chord between its two loop vertices
    X, T = div.X, div.T
    e = np.unique(np.sort(np.r_[T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]], axis=1), axis=0)
    adj: dict[int, set[int]] = {}
    for u, v in e.tolist():
        adj.setdefault(u, set()).add(v)
        adj.setdefault(v, set()).add(u)
    scale = float(np.ptp(P, axis=0).max())
    for i, j in folds.tolist():
        d = P[j] - P[i]
        L = float(np.linalg.norm(d))
        on = np.flatnonzero(np.linalg.norm(np.cross(X - P[i], d / L), axis=1) < 1e-9 * scale)
        t = (X[on] - P[i]) @ d / L**2
        on = on[(t > -1e-9) & (t < 1 + 1e-9)]
        chain = on[np.argsort((X[on] - P[i]) @ d)]
        assert chain[0] == i and chain[-1] == j
        assert all(b in adj[a] for a, b in zip(chain[:-1], chain[1:], strict=True))
        # divided into pieces of about the target length
        assert len(chain) - 1 == max(1, round(L / h))


def test_mean_value_layout_keeps_no_folds(full_search):
    # a loop waving 2 up and down four times, triangulated over all triangles: its development
    # overlaps itself, the patch is laid out by mean-value coordinates and keeps no fold (the
    # fill's conforming retry skips it)
    t = np.linspace(0, 2 * np.pi, 121)[:-1]
    P = np.c_[np.cos(t), np.sin(t), 2.0 * np.cos(4 * t)]
    h = float(np.linalg.norm(P - np.roll(P, -1, axis=0), axis=1).mean())
    Tc = LR._orient_patch(min_weight_triangulation(P, search="all"), len(P))
    assert _unfold(P, Tc) is None and len(LR._creases(P, Tc, LR.LIEPA_CREASE)) > 0
    assert LR._enclose_liepa(P, h, None, None).n_folds == 0


def test_divided_folds_points():
    Q = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0]])
    pts, segs = LR._divided_folds(Q, np.array([[0, 2], [1, 3]]), 1.0)
    # each diagonal (length 5) into 5 pieces: 4 new points each, after the loop
    assert pts.shape == (4 + 8, 2) and np.array_equal(pts[:4], Q)
    assert np.allclose(pts[4:8], np.outer(np.arange(1, 5) / 5, [4.0, 3.0]))
    assert segs.tolist()[:5] == [[0, 4], [4, 5], [5, 6], [6, 7], [7, 2]]
    assert segs.tolist()[5:] == [[1, 8], [8, 9], [9, 10], [10, 11], [11, 3]]
    # a fold shorter than the target stays one segment
    pts, segs = LR._divided_folds(Q, np.array([[0, 1]]), 10.0)
    assert len(pts) == 4 and segs.tolist() == [[0, 1]]


def test_fill_retries_an_intersecting_liepa_patch_conforming(monkeypatch):
    """A hole of trim_star cut at 12 l̄ (seed 2, hole 2) is enclosed by Liepa's triangulation
    (its planar patch intersects the surface); faired on the divided folds it intersects too
    (103 face pairs), meshed conforming to its folds it is faired fully and clean. Without the
    retry the hole ends with a patch that still intersects, kept with a note."""
    import meshrepair.fill.place as place
    from meshrepair.fill import fill_holes
    from meshrepair.holes.intersect import self_intersections

    m = read_mesh(DATA / "trim_star.ply")
    Vc, Fc, _, _ = cut_holes(m.V, m.F, 12.0, seed=2)

    def hole2(retry: bool):
        monkeypatch.setattr(place, "CONFORMING_RETRY", retry)
        r = fill_holes(Vc, Fc)
        return r, next(h for h in r.holes if h.index == 2)

    r, h = hole2(True)
    assert h.status == "filled" and h.reason == "liepa, triharmonic", h.reason
    assert h.n_intersections == 0 and h.note == ""
    assert len(self_intersections(r.V, r.F, np.arange(len(Fc), len(r.F)))) == 0
    r0, h0 = hole2(False)
    # without the retry: the fairing given up (the membrane or unfaired surface)
    assert h0.reason.endswith(("membrane", "unfaired", " faired")), h0.reason
    # and the fully faired patch lies closer to the cut surface (trim_star itself)
    from meshrepair.metrics import point_to_surface

    def dist(res, hole):
        new = np.flatnonzero(np.isin(res.F, np.arange(len(Vc), len(res.V))).any(axis=1))
        near = np.linalg.norm(res.V[res.F[new]].mean(axis=1) - res.V[hole.loop].mean(axis=0),
                              axis=1) < 2.0 * np.ptp(res.V[hole.loop], axis=0).max()
        return point_to_surface(res.V[res.F[new[near]]].mean(axis=1), m.V, m.F).mean()

    assert dist(r, h) < 0.8 * dist(r0, h0), (dist(r, h), dist(r0, h0))
