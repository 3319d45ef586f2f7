"""Smooth hole filling and inpainting of damaged regions (Sect. 5 of the paper), optionally with
denoising in the same solve.

Pipeline of :func:`fill_holes`:

1. *Detection and selection* (:mod:`meshrepair.holes`): boundary loops split into simple loops,
   the intended border kept (``keep_border``), ``exclude`` / ``holes`` / ``max_hole_size``.
2. *Trivial enclosing*: each selected loop gets a triangulated patch whose boundary is exactly the
   loop, with interior edges matching the loop's edge length and a membrane initial position
   (:func:`meshrepair.holes.enclose_holes`). The new vertices form the region ``S_D``. A hole
   whose patch intersects the surface (faired and membrane) is enclosed again with the next
   method of :data:`ENCLOSE_ORDER` (Liepa's minimum-weight triangulation, faired, then on its
   own surface) before it is refused.
3. *Initial position* (``initial``): ``"bilaplacian"`` (default) moves the new vertices to the
   bi-Laplacian (thin-plate) fairing with the surrounding 1-ring as Dirichlet data, which continues
   the surrounding curvature into the hole; ``"harmonic"`` keeps the flat membrane. With
   ``triharmonic=True`` (default) the screened triharmonic fairing (two rings of the surround as
   data, curvature continuity; :mod:`meshrepair.holes.triharmonic`) is computed too and kept for
   each hole whose seam angle it lowers.
4. *Repair solve* with the shared :class:`~meshrepair.solver.ADMMSolver`: ``M_V = 0`` on the new
   vertices, ``M_E`` forced to 0 (edge-Willmore) on every edge of a new face (the patch interior
   and the loop itself, so the patch joins its surround smoothly), the dihedral-threshold mask
   elsewhere.

   * ``denoise=False`` (fill only): all original vertices are ``fixed``; only the patch moves.
     The solve runs on the patches plus ``rings`` rings of surrounding faces (faces further away
     cannot influence the patch: their vertices are fixed) with one stage whose mask is
     ``"none"``: every free edge is edge-Willmore, which is what the paper prescribes inside
     ``S_D``; fixed faces far from the patch contribute constants only.
   * ``denoise=True`` (fill + denoise): the whole mesh is solved with the denoising schedule of
     :func:`meshrepair.denoise.default_stages` and λ from the estimated noise
     (:func:`meshrepair.denoise.lambda_from_noise`); ``M_V = 1`` outside the patches.

:func:`inpaint` first removes a damaged region (its faces), then fills the holes that this opens.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from .errors import MeshRepairError
from .holes import (
    LIEPA_MAX_LOOP,
    HoleReport,
    enclose_holes,
    fair_vertices,
    select_holes,
    self_intersections,
)
from .holes.budget import check_budget, check_fill_options
from .holes.creases import find_crease_routes
from .holes.triharmonic import fair_triharmonic
from .solver import ADMMSolver, SolverOptions, Stage
from .topology import edge_topology

log = logging.getLogger(__name__)

__all__ = ["FillResult", "fill_holes", "inpaint", "region_mask"]

INITIAL_MODES = ("bilaplacian", "harmonic")

ENCLOSE_ORDER: tuple[str, ...] = ("auto", "liepa")
"""Enclosing methods (:func:`meshrepair.holes.enclose_loop`) in the order they are tried on a
hole: the next one when the patch of the previous one intersects the surface both faired and
unfaired. ``"auto"``: planar projection + membrane; ``"liepa"``: Liepa's minimum-weight
triangulation refined on its own surface (loops up to :data:`meshrepair.holes.LIEPA_MAX_LOOP`
vertices). Planar first: Liepa first was less accurate after fairing on the smooth benchmark
cases (docs/holes.md, section 6)."""

_METHOD_NAMES = {"auto": "planar projection", "liepa": "minimum-weight triangulation"}


def _enclose_methods(hole) -> list[str]:
    """Enclosing methods to try on ``hole``, in order (``"liepa"`` only up to
    :data:`meshrepair.holes.LIEPA_MAX_LOOP` boundary vertices)."""
    out = [m for m in ENCLOSE_ORDER if m != "liepa" or hole.n_boundary <= LIEPA_MAX_LOOP]
    return out or ["auto"]


@dataclass
class FillResult:
    """Result of :func:`fill_holes` and :func:`inpaint`.

    Attributes
    ----------
    V : (nV', 3) float64
        Vertices: the kept original vertices first, in their original order, then the new
        vertices (hole by hole).
    F : (nF', 3) int64
        Faces: the kept original faces first, in their original order, then the new faces.
    M_V : (nV',) float64
        Fidelity mask: 0 on new vertices (the region ``S_D``), 1 elsewhere.
    M_E : (nE,) bool
        Sharp-edge mask of the last solver stage (False on every edge of a new face).
    edges : (nE, 2) int64
        The edges ``M_E`` refers to (``edge_topology(F).edges``).
    history : list of dict
        One entry per ADMM iteration (see :class:`meshrepair.solver.SolverResult`).
    holes : list of HoleReport
        One report per boundary loop of the (cut) input: filled or skipped, and why.
    new_vertices : (m,) int64
        Indices of the new vertices in ``V``.
    new_faces : (t,) int64
        Indices of the new faces in ``F``.
    vertex_map : (nV_in,) int64
        Output index of every input vertex, -1 for dropped ones (only :func:`inpaint` drops the
        vertices of the removed region); the identity for :func:`fill_holes`.
    removed_faces : (r,) int64
        Input faces removed by :func:`inpaint` (empty for :func:`fill_holes`).
    iterations : int
    stop_reason : str
    params : dict
        The options actually used.
    timings : dict
        Seconds per step (``enclose``, ``initial``, ``solve``, ``total``).
    """

    V: np.ndarray
    F: np.ndarray
    M_V: np.ndarray
    M_E: np.ndarray
    edges: np.ndarray
    history: list[dict] = field(default_factory=list)
    holes: list[HoleReport] = field(default_factory=list)
    new_vertices: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    new_faces: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    vertex_map: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    removed_faces: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    iterations: int = 0
    stop_reason: str = ""
    params: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)

    @property
    def n_filled(self) -> int:
        """Number of holes filled."""
        return sum(h.status == "filled" for h in self.holes)

    @property
    def n_skipped(self) -> int:
        """Number of holes left open."""
        return sum(h.status != "filled" for h in self.holes)

    @property
    def filled_mask(self) -> np.ndarray:
        """(nV',) uint8: 1 on new vertices (for a PLY vertex attribute)."""
        m = np.zeros(len(self.V), np.uint8)
        m[self.new_vertices] = 1
        return m

    @property
    def mesh(self):
        """The result as a ``trimesh.Trimesh`` (no processing, same vertex order)."""
        import trimesh

        return trimesh.Trimesh(self.V, self.F, process=False)

    def summary(self) -> str:
        """Human-readable summary: holes found, filled, skipped and why."""
        lines = [f"{len(self.holes)} holes found, {self.n_filled} filled, {self.n_skipped} "
                 f"skipped; {len(self.new_vertices)} new vertices, {len(self.new_faces)} new "
                 f"faces"]
        if len(self.removed_faces):
            lines.insert(0, f"removed {len(self.removed_faces)} faces of the damaged region")
        for h in self.holes:
            what = (f"filled ({h.reason}; {h.n_new_vertices} vertices, {h.n_new_faces} faces)"
                    if h.status == "filled" else f"skipped: {h.reason}")
            lines.append(f"  hole {h.index}: {h.n_boundary} boundary edges, length "
                         f"{h.length:.6g}: {what}")
        return "\n".join(lines)


# ------------------------------------------------------------------------------------------------
# shared core
# ------------------------------------------------------------------------------------------------


def _ring_faces(F: np.ndarray, seed_vertices: np.ndarray, nV: int, rings: int) -> np.ndarray:
    """Faces within ``rings`` face-rings of the seed vertices, bool ``(nF,)``."""
    vm = np.zeros(nV, bool)
    vm[seed_vertices] = True
    fm = vm[F].any(axis=1)
    for _ in range(rings):
        vm[F[fm].ravel()] = True
        fm = vm[F].any(axis=1)
    return fm


def _blocks(reports: list[HoleReport], nV: int, nF: int) -> dict[int, tuple[np.ndarray,
                                                                             np.ndarray]]:
    """New vertex and face index ranges of each filled hole (patches are appended in order)."""
    out = {}
    ov, of = nV, nF
    for rep in reports:
        if rep.status == "filled" and (rep.n_new_vertices or rep.n_new_faces):
            out[rep.index] = (np.arange(ov, ov + rep.n_new_vertices, dtype=np.int64),
                              np.arange(of, of + rep.n_new_faces, dtype=np.int64))
            ov += rep.n_new_vertices
            of += rep.n_new_faces
    return out


def _drop_patches(V1: np.ndarray, F1: np.ndarray, reports: list[HoleReport], nV: int, nF: int,
                  drop: dict[int, str]) -> tuple[np.ndarray, np.ndarray]:
    """Remove the patches of the holes in ``drop`` (index -> reason) and mark them skipped."""
    blocks = _blocks(reports, nV, nF)
    keepV = np.ones(len(V1), bool)
    keepF = np.ones(len(F1), bool)
    for i in drop:
        keepV[blocks[i][0]] = False
        keepF[blocks[i][1]] = False
    remap = np.cumsum(keepV) - 1
    for rep in reports:
        if rep.index in drop:
            rep.status, rep.reason = "skipped", drop[rep.index]
            rep.n_new_vertices = rep.n_new_faces = 0
            rep.n_creases = 0
            rep.sharp_edges = np.empty((0, 2), np.int64)
        elif len(rep.sharp_edges):
            rep.sharp_edges = remap[rep.sharp_edges]
    return V1[keepV], remap[F1[keepF]]


def _intersecting(V: np.ndarray, F: np.ndarray, faces: np.ndarray,
                  ignore: np.ndarray | None = None, pairs: np.ndarray | None = None) -> int:
    """Face pairs involving ``faces`` that intersect, not counting faces marked in ``ignore``
    (``pairs``: precomputed pairs of a superset of ``faces``, filtered instead of recomputed)."""
    if pairs is None:
        pairs = self_intersections(V, F, faces)
    elif len(pairs):
        mine = np.zeros(len(F), bool)
        mine[faces] = True
        pairs = pairs[mine[pairs].any(axis=1)]
    if ignore is not None and len(pairs):
        pairs = pairs[~ignore[pairs].any(axis=1)]
    return len(pairs)


BLEND_STEPS = (0.5, 0.25)
"""When the faired patch intersects the surround, these fractions of the fairing (from the
initial surface) are tried before the initial surface itself."""

SEAM_RETRY_FACTOR = 1.5
SEAM_RETRY_MARGIN = 3.0
"""A planar patch whose mean dihedral angle across its loop exceeds
``SEAM_RETRY_FACTOR * surround + SEAM_RETRY_MARGIN`` degrees (surround: the original edges within
3 rings) is enclosed again by Liepa's triangulation and the smoother seam kept. Measured on the
peers benchmark (docs/holes.md): rocker_arm r=8 seams 25.3° / 19.6° vs surround 7.9° / 8.4°
(Liepa: 8.6° / 5.8°, patch distance 0.62× / 0.59×), trim_star crease r=8 14.4° vs 5.3° (Liepa
7.0°, 0.85×); unchanged below the rule: spot (1.7° vs 1.6°), twelve (5.6° vs 2.1°)."""


def _seam_angle(V: np.ndarray, F: np.ndarray, faces: np.ndarray, nF: int, ring: bool = False):
    """Mean dihedral angle (degrees) across the loop edges of the patch ``faces`` (edges between
    one of them and an original face); with ``ring``, also that of the original edges within 3
    rings of the patch."""
    from .geometry import dihedral_angles, face_normals

    near_v = np.zeros(len(V), bool)
    near_v[F[faces].ravel()] = True
    reach = near_v.copy()
    for _ in range(4 if ring else 1):
        reach[F[reach[F].any(axis=1)].ravel()] = True
    fl = np.flatnonzero(reach[F].any(axis=1))
    Fl = F[fl]
    topo = edge_topology(Fl, len(V))
    ang = dihedral_angles(face_normals(V, Fl), topo)
    mine = np.isin(fl, faces)
    a, b = topo.edge_faces[:, 0], topo.edge_faces[:, 1]
    inner = b >= 0
    b = np.maximum(b, 0)
    seam_e = inner & (mine[a] != mine[b]) & (fl[np.where(mine[a], b, a)] < nF)
    seam = float(ang[seam_e].mean()) if seam_e.any() else 0.0
    if not ring:
        return seam
    ring_v = near_v.copy()
    for _ in range(3):
        ring_v[Fl[ring_v[Fl].any(axis=1)].ravel()] = True
    orig = (fl < nF) & ring_v[Fl].all(axis=1)
    sur = inner & orig[a] & orig[b]
    return seam, float(ang[sur].mean()) if sur.any() else 0.0


def _sharp_vertices(V: np.ndarray, F: np.ndarray, th: float, nV: int) -> np.ndarray:
    """(nV,) bool: vertices on an edge with dihedral angle above ``th``."""
    from .geometry import face_normals, sharp_edge_mask

    topo = edge_topology(F, nV)
    m = sharp_edge_mask(face_normals(V, F), topo, th).astype(bool)
    out = np.zeros(nV, bool)
    out[topo.edges[m].ravel()] = True
    return out


def _crease_edges(reports: list[HoleReport]) -> np.ndarray:
    """All patch edges on routed creases, ``(q, 2)`` output vertex indices."""
    parts = [r.sharp_edges for r in reports if r.status == "filled" and len(r.sharp_edges)]
    return np.concatenate(parts) if parts else np.empty((0, 2), np.int64)


def _edge_ids(topo, pairs: np.ndarray, n: int) -> np.ndarray:
    """Indices in ``topo.edges`` of the vertex pairs ``(q, 2)`` (pairs that are no edge are
    dropped)."""
    if len(pairs) == 0:
        return np.empty(0, np.int64)
    e = np.sort(topo.edges, axis=1)
    code = e[:, 0] * np.int64(n) + e[:, 1]
    order = np.argsort(code)
    p = np.sort(np.asarray(pairs, np.int64), axis=1)
    want = p[:, 0] * np.int64(n) + p[:, 1]
    pos = np.clip(np.searchsorted(code[order], want), 0, len(code) - 1)
    hit = code[order][pos] == want
    return order[pos[hit]]


def _finite_rows(V: np.ndarray, Vsafe: np.ndarray, rows: np.ndarray, what: str) -> np.ndarray:
    """``V`` with the non-finite ``rows`` replaced by ``Vsafe`` (logged)."""
    bad = rows[~np.isfinite(V[rows]).all(axis=1)]
    if len(bad):
        log.warning("%s gave %d non-finite vertex positions; kept the previous ones", what,
                    len(bad))
        V = V.copy()
        V[bad] = Vsafe[bad]
    return V


def _fill_core(V: np.ndarray, F: np.ndarray, holes, skip: dict[int, str], *, denoise: bool,
               initial: str, refine: bool, edge_length: float | None, lam: float | None,
               th: float, a: float, max_iter: int, tol: float, rings: int, relax: float,
               inner_solver: str, inner_iters: int, check: bool,
               callback: Callable[[dict], None] | None,
               progress: Callable[[int, int], None] | None = None,
               creases: bool = True, curvature: bool = True,
               triharmonic: bool = True) -> FillResult:
    from .geometry import face_normals, sharp_edge_mask

    t0 = time.perf_counter()
    nV, nF = len(V), len(F)
    by_index = {h.index: h for h in holes}
    stage: dict[int, int] = {}  # hole index -> position in its list of enclosing methods
    t_enclose = t_initial = 0.0
    first = True
    seam_prev: dict[int, float] = {}  # hole -> seam angle of its planar patch (seam trial)
    locked: set[int] = set()
    revert: list[int] = []
    while True:
        ta = time.perf_counter()
        method = {h.index: _enclose_methods(h)[stage.get(h.index, 0)] for h in holes}
        if first:
            routes = find_crease_routes(V, F, holes, skip, th) if creases else {}
            sharp_v = np.flatnonzero(_sharp_vertices(V, F, th, nV))
        V1, F1, reports = enclose_holes(
            V, F, holes, skip, edge_length=edge_length, check=check, intersections=False,
            method=method, creases=routes,
            progress=None if progress is None or not first else progress)
        first = False
        tb = time.perf_counter()
        Vm = V1
        if initial == "bilaplacian" and len(V1) > nV:
            ce = _crease_edges(reports)
            on_crease = np.unique(ce)
            free = np.setdiff1d(np.arange(nV, len(V1)), on_crease)
            V1 = fair_vertices(V1, F1, free, order=2, weights="cotan", iterations=3,
                               exclude_rows=on_crease, curvature=curvature,
                               curvature_exclude=sharp_v)
            if triharmonic:
                # curvature-continuous (triharmonic) candidate, two rings of the surround as
                # data; kept per hole where it meets the surround more smoothly (section 3d)
                Vt = fair_triharmonic(V1, F1, free, iterations=3,
                                      exclude_rows=np.union1d(on_crease, sharp_v))
                Vt = _finite_rows(Vt, V1, np.arange(nV, len(V1)), "the triharmonic fairing")
                V1 = V1.copy()
                by_rep = {r.index: r for r in reports}
                for i, (bv, bf) in _blocks(reports, nV, nF).items():
                    s_thin = _seam_angle(V1, F1, bf, nF)
                    s_tri = _seam_angle(Vt, F1, bf, nF)
                    if s_tri < s_thin:
                        V1[bv] = Vt[bv]
                        by_rep[i].reason += ", triharmonic"
                        log.info("hole %d: triharmonic fairing kept (seam %.2f° vs thin plate "
                                 "%.2f°)", i, s_tri, s_thin)
            V1 = _finite_rows(V1, Vm, np.arange(nV, len(V1)), "the thin-plate fairing")
        drop: dict[int, str] = {}
        retry: list[int] = []
        if check:
            dropped = np.zeros(len(F1), bool)  # faces of patches already refused
            blocks = _blocks(reports, nV, nF)
            all_new = np.arange(nF, len(F1))
            pairs0 = self_intersections(V1, F1, all_new) if len(all_new) else None
            by_rep = {r.index: r for r in reports}
            for i, (bv, bf) in blocks.items():
                rep = by_rep[i]
                n_x = _intersecting(V1, F1, bf, dropped, pairs=pairs0)
                if n_x and initial == "bilaplacian":
                    # keep as much of the fairing as stays clear of the surround: the patch
                    # moved back towards its initial surface by halves, then the initial one
                    unfaired = "unfaired" if method[i] == "liepa" else "membrane"
                    Vf = V1[bv].copy()
                    V1 = V1.copy()
                    for frac in BLEND_STEPS:
                        V1[bv] = Vm[bv] + frac * (Vf - Vm[bv])
                        n_x = _intersecting(V1, F1, bf, dropped)
                        if not n_x:
                            log.info("hole %d: the faired patch intersects the mesh; kept %g of "
                                     "the fairing", i, frac)
                            rep.reason += f", {frac:g} faired"
                            break
                    if n_x:
                        log.info("hole %d: the faired patch intersects the mesh; using the %s",
                                 i, "unfaired surface" if unfaired == "unfaired" else "membrane")
                        V1[bv] = Vm[bv]
                        n_x = _intersecting(V1, F1, bf, dropped)
                        if not n_x:
                            rep.reason += f", {unfaired}"
                if not n_x:
                    # choose by measurement: a planar patch meeting its surround at a kink is
                    # tried again with Liepa's triangulation, and the smoother seam is kept
                    if i in seam_prev and method[i] == "liepa" and i not in locked:
                        seam = _seam_angle(V1, F1, bf, nF)
                        if not seam < seam_prev[i]:
                            log.info("hole %d: the minimum-weight patch's seam (%.1f°) is no "
                                     "smoother than the planar one (%.1f°); keeping the planar",
                                     i, seam, seam_prev[i])
                            revert.append(i)
                        locked.add(i)
                    elif (initial == "bilaplacian" and method[i] == "auto" and i not in locked
                          and rep.n_creases == 0 and not rep.reason.startswith("annulus")
                          and len(_enclose_methods(by_index[i])) > 1):
                        seam, ring = _seam_angle(V1, F1, bf, nF, ring=True)
                        if seam > SEAM_RETRY_FACTOR * ring + SEAM_RETRY_MARGIN:
                            log.info("hole %d: the planar patch meets its surround at %.1f° "
                                     "(surround %.1f°); trying the minimum-weight "
                                     "triangulation", i, seam, ring)
                            seam_prev[i] = seam
                            retry.append(i)
                    continue
                if i in seam_prev and method[i] == "liepa" and i not in locked:
                    locked.add(i)  # the seam trial intersects: back to the planar patch
                    revert.append(i)
                    continue
                dropped[bf] = True
                nxt = stage.get(i, 0) + 1
                if nxt < len(_enclose_methods(by_index[i])) and not rep.reason.startswith(
                        "annulus"):
                    log.info("hole %d: the %s patch intersects the mesh (%d face pairs); "
                             "trying %s", i, method[i], n_x, _enclose_methods(by_index[i])[nxt])
                    retry.append(i)
                    continue
                tried = ", ".join(_METHOD_NAMES[m] for m in _enclose_methods(by_index[i])
                                  ) if not rep.reason.startswith("annulus") else "annulus"
                drop[i] = (f"the patch would intersect the surface ({n_x} face pairs; tried: "
                           f"{tried}): the loop is too twisted for a direct fill (e.g. it wraps "
                           "round a thin wall or is the border of an open scan: use "
                           "keep_border); exclude it or fill it manually")
        t_enclose += tb - ta
        t_initial += time.perf_counter() - tb
        if not retry and not revert:
            break
        for i in retry:
            stage[i] = stage.get(i, 0) + 1
        for i in revert:
            stage[i] = 0
        revert = []
    if drop:
        V1, F1 = _drop_patches(V1, F1, reports, nV, nF, drop)
    t2 = time.perf_counter()
    new_v = np.arange(nV, len(V1), dtype=np.int64)
    new_f = np.arange(nF, len(F1), dtype=np.int64)
    M_V = np.ones(len(V1))
    M_V[new_v] = 0.0
    topo = edge_topology(F1, len(V1))
    patch_edges = np.zeros(topo.n_edges, bool)
    patch_edges[topo.face_edges[new_f].ravel()] = True
    edge_force = np.full(topo.n_edges, -1, np.int8)
    edge_force[patch_edges] = 0
    crease_e = _edge_ids(topo, _crease_edges(reports), len(V1))
    edge_force[crease_e] = 1  # routed creases: the MC penalty rebuilds them sharp
    history: list[dict] = []
    iterations = 0
    stop_reason = "no solve"
    params: dict = {"denoise": denoise, "initial": initial, "refine": refine, "th": th}
    M_E = sharp_edge_mask(face_normals(V1, F1), topo, th).astype(bool) & ~patch_edges
    M_E[crease_e] = True
    V_before = V1
    if denoise:
        from .denoise import default_stages, lambda_from_noise
        from .noise import estimate_noise

        gamma = estimate_noise(V, F)
        lam_used = lambda_from_noise(gamma) if lam is None else float(lam)
        opts = SolverOptions(lam=lam_used, th=th, stages=default_stages(a=a), tol=tol,
                             inner_solver=inner_solver, inner_iters=inner_iters,
                             mask_update_every=3)
        solver = ADMMSolver(F1, len(V1), M_V=M_V, edge_force=edge_force, options=opts, topo=topo)
        res = solver.solve(V1, callback=callback)
        V1 = res.V
        M_E = np.asarray(res.M_E, bool)
        history, iterations, stop_reason = res.history, res.iterations, res.stop_reason
        params.update(lam=lam_used, noise_estimate=gamma, a=a)
    elif refine and len(new_v):
        # local solve: the patches and `rings` rings of fixed faces around them
        fm = _ring_faces(F1, new_v, len(V1), rings)
        fidx = np.flatnonzero(fm)
        used = np.unique(F1[fidx].ravel())
        loc = -np.ones(len(V1), np.int64)
        loc[used] = np.arange(len(used))
        Fl = loc[F1[fidx]]
        fixed = M_V[used] > 0
        topo_l = edge_topology(Fl, len(used))
        ef = np.full(topo_l.n_edges, -1, np.int8)
        ef[topo_l.face_edges[fidx >= nF].ravel()] = 0
        ce = _crease_edges(reports)
        if len(ce):
            ef[_edge_ids(topo_l, loc[ce], len(used))] = 1
        stage = Stage(a=a, eps=1.2, beta2_ratio=5.0, mask="none", max_iter=max_iter,
                      min_iter=min(max_iter, 30), relax=relax, name="fill")
        opts = SolverOptions(lam=1.0, th=th, stages=(stage,), tol=tol, inner_solver=inner_solver,
                             inner_iters=inner_iters)
        solver = ADMMSolver(Fl, len(used), M_V=M_V[used], edge_force=ef, fixed=fixed,
                            options=opts, topo=topo_l)
        res = solver.solve(V1[used], callback=callback)
        V1 = V1.copy()
        V1[used[~fixed]] = res.V[~fixed]
        V1 = _finite_rows(V1, V_before, new_v, "the ADMM solve")
        history, iterations, stop_reason = res.history, res.iterations, res.stop_reason
        params.update(rings=rings, max_iter=max_iter, relax=relax)
    t3 = time.perf_counter()
    if check:
        pairs1 = self_intersections(V1, F1, new_f) if len(new_f) else None
        by_rep = {r.index: r for r in reports}
        for i, (bv, bf) in _blocks(reports, nV, nF).items():
            rep = by_rep[i]
            rep.n_intersections = _intersecting(V1, F1, bf, pairs=pairs1)
            if rep.n_intersections and not denoise and V1 is not V_before:
                V1[bv] = V_before[bv]
                rep.n_intersections = _intersecting(V1, F1, bf)
                log.warning("hole %d: the solve made the patch intersect the mesh; kept the "
                            "initial patch", i)
            if rep.n_intersections:
                log.warning("hole %d: %d face pairs of the patch intersect the mesh", i,
                            rep.n_intersections)
    return FillResult(
        V=V1, F=F1, M_V=M_V, M_E=M_E, edges=topo.edges.copy(),
        history=history, holes=reports, new_vertices=new_v, new_faces=new_f,
        vertex_map=np.arange(nV, dtype=np.int64), iterations=iterations,
        stop_reason=stop_reason, params=params,
        timings={"enclose": t_enclose, "initial": t_initial, "solve": t3 - t2,
                 "total": time.perf_counter() - t0},
    )


def _check_options(initial: str, max_iter: int, rings: int, **numeric) -> None:
    if initial not in INITIAL_MODES:
        raise MeshRepairError(f"initial must be one of {INITIAL_MODES}, got {initial!r}")
    check_fill_options(max_iter=max_iter, rings=rings, **numeric)


# ------------------------------------------------------------------------------------------------
# public API
# ------------------------------------------------------------------------------------------------


def fill_holes(
    V,
    F=None,
    *,
    max_hole_size: int | None = None,
    keep_border: bool = False,
    exclude: Sequence[int] = (),
    holes: Sequence[int] | None = None,
    denoise: bool = False,
    initial: str = "bilaplacian",
    refine: bool = True,
    edge_length: float | None = None,
    lam: float | None = None,
    th: float = 30.0,
    a: float = 10.0,
    max_iter: int = 150,
    tol: float = 1e-5,
    rings: int = 3,
    relax: float = 0.0,
    inner_solver: str = "armijo",
    inner_iters: int = 3,
    check: bool = True,
    callback: Callable[[dict], None] | None = None,
    progress: Callable[[int, int], None] | None = None,
    creases: bool = True,
    curvature: bool = True,
    triharmonic: bool = True,
) -> FillResult:
    """Fill the holes of a triangle mesh smoothly, optionally denoising it in the same solve.

    Parameters
    ----------
    V : (nV, 3) float array, or a ``trimesh.Trimesh`` (then ``F`` is omitted)
    F : (nF, 3) int array
    max_hole_size : int, optional
        Fill only holes with at most this many boundary vertices (= edges).
    keep_border : bool
        Leave the longest loop open (the intended border of a scan or of a model cut open).
        Independently of it, a loop recognised as the open border of its surface by its size
        (:func:`meshrepair.holes.border.find_borders`) is left open with the reason, unless it
        is listed in ``holes``.
    exclude : sequence of int
        Hole indices (see :func:`meshrepair.holes.find_holes`: longest first) to leave open.
    holes : sequence of int, optional
        Fill only these holes.
    denoise : bool
        Also denoise the rest of the mesh in the same ADMM solve (``M_V = 1`` outside the holes,
        λ from the estimated noise unless ``lam`` is given); otherwise the original vertices do not
        move.
    initial : ``"bilaplacian"`` or ``"harmonic"``
        Initial position of the new vertices: thin-plate fairing with the surrounding ring as
        boundary condition (curved), or the membrane of the enclosing step (flat).
    refine : bool
        Run the ADMM solve (always done when ``denoise=True``).
    edge_length : float, optional
        Target edge length in the patches (default: each loop's mean edge length).
    lam : float, optional
        Fidelity weight λ (``denoise=True`` only).
    th : float
        Dihedral threshold (degrees) of the sharp-edge mask outside the patches.
    a : float
        MC non-convexity of the feature stage (``denoise=True``) / scale of β1 (fill only).
    max_iter : int
        ADMM iterations of the fill-only solve.
    tol : float
        Stopping tolerance (rule (35)).
    rings : int
        Rings of fixed faces around the patches included in the fill-only solve.
    relax : float
        Tangential relaxation weight per fill-only ADMM iteration (0 disables).
    inner_solver, inner_iters : V-subproblem solver and its iterations per ADMM iteration.
    check : bool
        Refuse patches that would intersect or lie on the surface, and count intersections of the
        final patches (``HoleReport.n_intersections``). A patch that intersects is tried
        faired, then unfaired, then with the next enclosing method of :data:`ENCLOSE_ORDER`
        (``HoleReport.reason`` says which was kept: e.g. ``"plane"``, ``"plane, membrane"``,
        ``"liepa"``, ``"liepa, unfaired"``) before the hole is refused.
    callback : called with each ADMM history entry.
    progress : called as ``progress(done, total)`` before each selected hole is enclosed (the
        CLI feeds a progress bar over holes with it).
    creases : bool
        Continue the sharp creases (dihedral angle above ``th``) that end on a hole's loop
        through the patch: paired across the hole or meeting at a corner, routed as
        constrained edges, placed on their curves and kept sharp by the MC penalty
        (:mod:`meshrepair.holes.creases`; ``HoleReport.n_creases``).
    curvature : bool
        With ``initial="bilaplacian"``: curvature continuity (the patch's Laplacian fitted to
        the surround's mean curvature interpolated over it, :func:`meshrepair.holes.fair_vertices`
        ``curvature=True``); False gives the plain thin plate.
    triharmonic : bool
        With ``initial="bilaplacian"``: also compute the triharmonic (curvature-continuous)
        fairing with two rings of the surround as data
        (:func:`meshrepair.holes.triharmonic.fair_triharmonic`) and keep it for each hole whose
        seam angle it lowers (``", triharmonic"`` in the hole's reason).

    Returns
    -------
    FillResult
        Original vertices and faces first in their original order, the new ones after. The input
        arrays are never modified.

    Raises
    ------
    MeshRepairError
        For invalid meshes (:func:`meshrepair.validate.check_mesh`) or options (e.g. a hole index
        that does not exist, a non-finite or out-of-range number), or when the selected holes
        would need more than :data:`meshrepair.holes.budget.MAX_NEW_FACES` new faces (estimated
        before any work; the message gives the count).
    """
    from .holes import _find_holes
    from .holes.border import find_borders
    from .io import as_arrays
    from .validate import check_mesh

    V, F = as_arrays(V, F)
    check_mesh(V, F, name="input mesh")
    _check_options(initial, max_iter, rings, edge_length=edge_length, lam=lam, th=th, a=a,
                   tol=tol, relax=relax, inner_iters=inner_iters)
    found = _find_holes(V, F)
    borders = find_borders(V, F, found)
    skip = select_holes(found, max_hole_size=max_hole_size, keep_border=keep_border,
                        exclude=exclude, indices=holes, borders=borders)
    check_budget([h for h in found if h.index not in skip], edge_length, what="fill_holes")
    log.info("fill_holes: %d holes found, %d selected%s", len(found), len(found) - len(skip),
             f" ({len(borders)} open border(s) left open)" if borders else "")
    res = _fill_core(V, F, found, skip, denoise=denoise, initial=initial, refine=refine,
                     edge_length=edge_length, lam=lam, th=th, a=a, max_iter=int(max_iter),
                     tol=tol, rings=int(rings), relax=relax, inner_solver=inner_solver,
                     inner_iters=inner_iters, check=check, callback=callback,
                     progress=progress, creases=creases, curvature=curvature,
                     triharmonic=triharmonic)
    res.params.update(max_hole_size=max_hole_size, keep_border=keep_border,
                      exclude=list(exclude), holes=None if holes is None else list(holes))
    return res


def region_mask(V: np.ndarray, region) -> np.ndarray:
    """Per-vertex bool mask of a region specification.

    Parameters
    ----------
    V : (nV, 3) float
    region : one of
        * a bool array of length nV (or a 0/1 array of length nV);
        * integer vertex indices;
        * ``("sphere", center, radius)``: vertices with ``|v - center| <= radius``;
        * ``("box", lo, hi)``: vertices with ``lo <= v <= hi`` component-wise.

    Returns
    -------
    (nV,) bool
    """
    V = np.asarray(V, dtype=np.float64)
    nV = len(V)
    if isinstance(region, tuple) and len(region) >= 1 and isinstance(region[0], str):
        kind = region[0].lower()
        try:
            if kind == "sphere" and len(region) == 3:
                c = np.asarray(region[1], dtype=np.float64).reshape(3)
                r = float(region[2])
                if not (np.isfinite(c).all() and np.isfinite(r) and r > 0):
                    raise ValueError
                return np.linalg.norm(V - c, axis=1) <= r
            if kind == "box" and len(region) == 3:
                lo = np.asarray(region[1], dtype=np.float64).reshape(3)
                hi = np.asarray(region[2], dtype=np.float64).reshape(3)
                if not (np.isfinite(lo).all() and np.isfinite(hi).all() and (lo <= hi).all()):
                    raise ValueError
                return ((V >= lo) & (V <= hi)).all(axis=1)
        except (ValueError, TypeError):
            pass
        raise MeshRepairError(
            f"invalid region {region!r}: use ('sphere', (x, y, z), radius > 0) or "
            "('box', (x0, y0, z0), (x1, y1, z1)) with x0 <= x1, y0 <= y1, z0 <= z1")
    from .io import read_vertex_mask

    return read_vertex_mask(np.asarray(region), nV)


def _remove_region(F: np.ndarray, nV: int, vmask: np.ndarray, max_rounds: int = 20
                   ) -> tuple[np.ndarray, list[str]]:
    """Faces to remove for a damaged vertex region, bool ``(nF,)``, and notes.

    Removed: every face with a corner in the region; then, repeatedly, kept faces left with two
    or three boundary edges next to the removed ones (dangling ears) and all faces around a vertex
    the removal left pinched (its remaining faces form several fans), so the holes are bounded by
    simple loops; finally kept pieces that the removal cut off and that are smaller than the
    removed area around them (islands inside the region).
    """
    from .validate import check_mesh  # noqa: F401  (validated by the caller)

    removed = vmask[F].any(axis=1)
    notes: list[str] = []
    n_ear = n_pinch = n_island = 0
    for _ in range(max_rounds):
        changed = False
        keep = np.flatnonzero(~removed)
        if len(keep) == 0:
            break
        topo = edge_topology(F[keep], nV)
        nb = topo.boundary[topo.face_edges].sum(axis=1)
        # ears next to the removed region: kept faces with >= 2 boundary edges that were interior
        touch = np.zeros(nV, bool)
        touch[F[removed].ravel()] = True
        ear = (nb >= 2) & touch[F[keep]].any(axis=1)
        if ear.any():
            removed[keep[ear]] = True
            n_ear += int(ear.sum())
            changed = True
            continue
        pinched = _pinched(F[keep], nV) & touch
        if pinched.any():
            sel = pinched[F[keep]].any(axis=1)
            removed[keep[sel]] = True
            n_pinch += int(sel.sum())
            changed = True
            continue
        if not changed:
            break
    # islands: kept components cut off by the removal and smaller than the removed area
    from .topology import connected_components

    keep = np.flatnonzero(~removed)
    if len(keep):
        n0, lab0 = connected_components(F, nV)
        n1, lab1 = connected_components(F[keep], nV)
        if n1 > n0:
            comp_of_face = lab1[F[keep, 0]]
            sizes = np.bincount(comp_of_face, minlength=n1)
            orig_of_comp = np.zeros(n1, np.int64)
            orig_of_comp[comp_of_face] = lab0[F[keep, 0]]
            n_removed_orig = np.bincount(lab0[F[removed, 0]], minlength=n0)
            for oc in np.unique(orig_of_comp):
                parts = np.flatnonzero((orig_of_comp == oc) & (sizes > 0))
                if len(parts) <= 1:
                    continue
                biggest = parts[np.argmax(sizes[parts])]
                for p in parts:
                    if p != biggest and sizes[p] < n_removed_orig[oc]:
                        sel = comp_of_face == p
                        removed[keep[sel]] = True
                        n_island += int(sel.sum())
    if n_ear:
        notes.append(f"{n_ear} dangling faces next to the region removed")
    if n_pinch:
        notes.append(f"{n_pinch} faces around vertices the removal left pinched removed")
    if n_island:
        notes.append(f"{n_island} faces of islands cut off inside the region removed")
    return removed, notes


def _pinched(F: np.ndarray, nV: int) -> np.ndarray:
    """(nV,) bool: vertices whose faces form more than one fan."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components as cc

    nF = len(F)
    he = np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2)
    # corner (f, k) sits at vertex F[f, k]; half-edge 3f+k goes F[f,k] -> F[f,k+1]
    key = np.sort(he, axis=1)
    code = key[:, 0] * np.int64(nV) + key[:, 1]
    order = np.argsort(code, kind="stable")
    cs = code[order]
    same = np.flatnonzero(cs[1:] == cs[:-1])
    h1, h2 = order[same], order[same + 1]

    def end_corner(h):
        return h - h % 3 + (h % 3 + 1) % 3

    a = np.r_[h1, end_corner(h1)]
    b = np.r_[end_corner(h2), h2]
    G = coo_matrix((np.ones(len(a)), (a, b)), shape=(3 * nF, 3 * nF))
    n, lab = cc(G.tocsr(), directed=False)
    gv = np.empty(n, np.int64)
    gv[lab] = F.ravel()
    return np.bincount(gv, minlength=nV) > 1


def inpaint(
    V,
    F,
    region,
    *,
    denoise: bool = False,
    initial: str = "bilaplacian",
    refine: bool = True,
    edge_length: float | None = None,
    lam: float | None = None,
    th: float = 30.0,
    a: float = 10.0,
    max_iter: int = 150,
    tol: float = 1e-5,
    rings: int = 3,
    relax: float = 0.0,
    inner_solver: str = "armijo",
    inner_iters: int = 3,
    check: bool = True,
    callback: Callable[[dict], None] | None = None,
    progress: Callable[[int, int], None] | None = None,
    creases: bool = True,
    curvature: bool = True,
    triharmonic: bool = True,
) -> FillResult:
    """Replace a damaged region of a mesh by a smooth patch.

    The faces with at least one corner in the region are removed (plus dangling faces, faces
    around vertices the removal would leave pinched, and small pieces it would cut off; see
    ``FillResult.removed_faces``); the vertices no longer used by any face are dropped; every hole
    this opens is filled as in :func:`fill_holes`. Holes the input already had are left alone.

    Parameters
    ----------
    V : (nV, 3) float array, or a ``trimesh.Trimesh`` (then pass ``F=None``)
    F : (nF, 3) int array or None
    region : vertex indices, a bool (or 0/1) mask of length nV, ``("sphere", center, radius)`` or
        ``("box", lo, hi)`` (see :func:`region_mask`).
    denoise, initial, refine, edge_length, lam, th, a, max_iter, tol, rings, relax, inner_solver,
    inner_iters, check, callback, progress, creases, curvature, triharmonic : as in
        :func:`fill_holes`.

    Returns
    -------
    FillResult
        ``vertex_map[i]`` is the output index of input vertex ``i`` (-1 if dropped); kept input
        vertices come first in their original order, the new vertices after. ``F`` holds the
        kept input faces in their original order, then the new faces. ``holes`` reports only the
        holes opened by the removal.

    Raises
    ------
    MeshRepairError
        For an invalid mesh or region, an empty region, or a region covering the whole mesh.
    """
    from .holes import _find_holes
    from .io import as_arrays
    from .validate import check_mesh

    V, F = as_arrays(V, F)
    check_mesh(V, F, name="input mesh")
    _check_options(initial, max_iter, rings, edge_length=edge_length, lam=lam, th=th, a=a,
                   tol=tol, relax=relax, inner_iters=inner_iters)
    nV, _nF = len(V), len(F)
    vmask = region_mask(V, region)
    if not vmask.any():
        raise MeshRepairError("the inpainting region contains no vertex of the mesh; check its "
                              "position and size (coordinates are in mesh units)")
    removed, notes = _remove_region(F, nV, vmask)
    if removed.all():
        raise MeshRepairError("the inpainting region covers the whole mesh; nothing would be "
                              "left to fill from: use a smaller region")
    for n in notes:
        log.info("inpaint: %s", n)
    keepF = F[~removed]
    used_before = np.zeros(nV, bool)
    used_before[F.ravel()] = True
    used_after = np.zeros(nV, bool)
    used_after[keepF.ravel()] = True
    drop = used_before & ~used_after
    vmap = np.full(nV, -1, np.int64)
    kept = np.flatnonzero(~drop)
    vmap[kept] = np.arange(len(kept))
    V2 = V[kept]
    F2 = vmap[keepF]
    # holes opened by the removal: loops through a vertex of a removed face
    found = _find_holes(V2, F2)
    old_edges: set[tuple[int, int]] = set()
    for h in _find_holes(V, F):
        old_edges.update(zip(h.vertices.tolist(), np.roll(h.vertices, -1).tolist(), strict=True))
    skip: dict[int, str] = {}
    for h in found:
        lp = kept[h.vertices]
        if set(zip(lp.tolist(), np.roll(lp, -1).tolist(), strict=True)) <= old_edges:
            skip[h.index] = "hole of the input, not part of the region (use fill_holes for it)"
    # removal that cuts a component into several large parts: refuse the loops of those parts
    from .topology import connected_components

    lab0 = connected_components(F, nV)[1]
    lab2 = connected_components(F2, len(V2))[1]
    part_orig: dict[int, set[int]] = {}
    for p, o in zip(lab2[F2[:, 0]].tolist(), lab0[kept[F2[:, 0]]].tolist(), strict=True):
        part_orig.setdefault(o, set()).add(p)
    cut_parts = {p for parts in part_orig.values() if len(parts) > 1 for p in parts}
    for h in found:
        if h.index not in skip and int(lab2[h.vertices[0]]) in cut_parts:
            n_parts = max(len(v) for v in part_orig.values())
            skip[h.index] = (f"the region cuts the mesh into {n_parts} parts; filling each cut "
                             "separately would cap the parts instead of rejoining them: use a "
                             "region that does not go all the way round")
    check_budget([h for h in found if h.index not in skip], edge_length, what="inpaint")
    res = _fill_core(V2, F2, found, skip, denoise=denoise, initial=initial, refine=refine,
                     edge_length=edge_length, lam=lam, th=th, a=a, max_iter=int(max_iter),
                     tol=tol, rings=int(rings), relax=relax, inner_solver=inner_solver,
                     inner_iters=inner_iters, check=check, callback=callback,
                     progress=progress, creases=creases, curvature=curvature,
                     triharmonic=triharmonic)
    res.vertex_map = vmap
    res.removed_faces = np.flatnonzero(removed).astype(np.int64)
    res.params.update(region_vertices=int(vmask.sum()), removal_notes=notes)
    res.holes = [h for h in res.holes if not h.reason.startswith("hole of the input")]
    return res
