"""Decisions of :func:`meshrepair.denoise` that do not depend on the resolution: the probe's
stopping rule and the CAD-part test.

**1. The probe's stopping rule.**

The robust stage and the probe of :func:`meshrepair.denoise` stop when the relative
change of the vertices ``rel = ||V^{k+1} - V^k||_F / ||V^k||_F`` (centred coordinates) falls
below ``switch_tol = 2e-4``. Every iteration of the ADMM moves a vertex by a local amount, in
mean edge lengths ``l̄``, so with ``q = rms_i |V_i - c| / l̄`` (the radius of the mesh in edge
lengths)

.. math:: rel = \\frac{\\mathrm{rms}_i |ΔV_i|}{\\mathrm{rms}_i |V_i - c|}
          = \\frac{1}{q} \\frac{\\mathrm{rms}_i |ΔV_i|}{l̄},

and the test ``rel < τ`` is ``rms |ΔV| / l̄ < τ q``: in edge units the tolerance grows with the
resolution (``q ∝ √n_V`` for a fixed shape). A mesh subdivided three times (``q`` × 8) stops its
probe after a fraction of the iterations the same surface gets at its own resolution, and
leaves the noise's terraces in, which the crease test reads as creases (a smooth mesh
subdivided three times at γ 0.5 reads about four times the creased edges of the same surface
at its own resolution). The tolerance in edge units is capped at its value on the finest mesh
of the benchmark set:

.. math:: τ_{eff} = τ \\min(1, Q_0 / q), \\qquad Q_0 = 45,

so ``rms |ΔV| / l̄ < τ \\min(q, Q_0)``: unchanged on every mesh with ``q ≤ 45`` (the shared
benchmark inputs read 14-44), the same step length in edge units on every finer mesh,
whatever its resolution.

A gate (:func:`gated_probe`): on a mesh with ``q > Q_0`` the probe first stops at ``τ``; it
goes on to ``τ_eff`` (for the iterations left) only when that probe's crease-supported region
is not empty, so a fine organic mesh that reads no crease keeps the relative stop. Phase 2
resumes phase 1's solver state (multipliers, penalties, normalisation, counters), so the two
phases are the iterates of a single probe run to ``τ_eff``.

**2. The CAD-part test.** :func:`meshrepair.denoise.rules.outside_weight` calls a mesh a CAD
part when the crease-supported region C
(chains dilated by 2 rings, :func:`meshrepair.denoise.regions.crease_support`) covers
``f = |C| / n_E ≥ 0.2`` of the edges. A crease network is a set of *lines* of the shape: its
length in edges grows as ``q`` and the edges of the mesh as ``q²``, so ``f ∝ 1/q`` on the same
part at another resolution (``f q`` stays within 10 % when a CAD part is subdivided once and
twice), and a finely resolved CAD part is read as organic. The chains of
an organic mesh come from the noise or its relief, not from lines of the shape, so the same
scaling cannot be applied to all of C. Only the chains that *look like* a crease between flat
sides count: a chain ``c`` of C is crease-like when its persistence ratio and side spread
(:func:`meshrepair.denoise.regions.chain_statistics`) pass the short-chain test of
:mod:`meshrepair.denoise.regions`, ``|p_c − 1| ≤ 0.05`` and ``s_c ≤ 5.5°``, whatever its length.
With ``f_g`` the share of C that belongs to crease-like chains (``f`` times their share of C's
chain edges), the fraction the same network would cover at the resolution ``Q_c = 15`` of the
coarsest benchmark meshes (q 15-16, where the threshold 0.2 was chosen) is

.. math:: f_{ref} = \\max\bigl(f,\\ f_g \\, q / Q_c\bigr),

and ``f_ref`` replaces ``f`` in every rule that reads the CAD-part decision (the outside
weight, the organic gates of the guidance, the coarse-to-fine low-pass and the data weight, and
the choice of the fidelity data). On the probe, CAD parts at any resolution read
``f_g q / Q_c`` = 0.28-0.59 and organic meshes 0.00-0.08 (their chains fail the test: side
spread 4.6-8.4°), so 0.2 separates them (docs/parameters.md).
"""

from __future__ import annotations

import numpy as np

SCALE_FREE_STOP = True
Q_REF = 45.0
SCALE_FREE_CAD = True
Q_CAD = 15.0


def radius_in_edges(V: np.ndarray, F: np.ndarray, edges: np.ndarray | None = None) -> float:
    """``q = rms_i |V_i − c| / l̄``, ``c`` the centroid of the referenced vertices and ``l̄``
    the mean length of the unique edges (``edges``, (nE, 2), when known: the faces' unique
    edges otherwise, which costs a sort)."""
    from meshrepair._kernels import edge_lengths_exact
    from meshrepair.mesh.geometry import mean_edge_length

    V = np.asarray(V, dtype=np.float64)
    used = np.zeros(len(V), bool)
    used[np.asarray(F).ravel()] = True
    Vu = V if used.all() else V[used]  # (the same rows in the same order: the same sums)
    X = Vu - Vu.mean(axis=0)
    el = mean_edge_length(V, F) if edges is None else float(edge_lengths_exact(V, edges).mean())
    return float(np.sqrt(np.mean(np.einsum("ij,ij->i", X, X))) / max(el, 1e-300))


def tolerance_factor(V: np.ndarray, F: np.ndarray, q_ref: float = Q_REF, *,
                     q: float | None = None) -> float:
    """``min(1, Q_0 / q)`` of the module docstring (1 when switched off); ``q`` from
    :func:`radius_in_edges` when not given."""
    if not SCALE_FREE_STOP:
        return 1.0
    q = radius_in_edges(V, F) if q is None else float(q)
    return float(min(1.0, q_ref / q)) if q > 0 else 1.0


def probe_tol(stage, q: float) -> float:
    """The probe's stopping tolerance ``stage.switch_tol · min(1, Q_0 / q)``, ``q`` the
    mesh's :func:`radius_in_edges`."""
    f = min(1.0, Q_REF / float(q)) if SCALE_FREE_STOP and q > 0 else 1.0
    return float(stage.switch_tol) * f

def crease_like_share(topo, N: np.ndarray, support: np.ndarray, *, th: float = 30.0) -> float:
    """``f_g`` of the module docstring: ``|C| / n_E`` times the share of C's chain edges in
    crease-like chains (``|p − 1| ≤ 0.05`` and ``s ≤ 5.5°``, any length).

    Parameters
    ----------
    topo : Topology
    N : (nF, 3) unit face normals of the probe
    support : (nE,) bool, the crease-supported region C of the same normals
    th : dihedral threshold of the creased edges, degrees
    """
    from meshrepair import _kernels as _k
    from meshrepair.denoise import regions as R

    if not support.any():
        return 0.0
    L = min(R.MIN_CHAIN, max(1, int(np.ceil(R.CHAIN_FRACTION * topo.n_edges))))
    cre = R.creased_edges(topo, N, th)
    chains = R.long_chains(topo, cre, L)
    if chains.any():
        chains = R.supported_chains(topo, N, cre, chains, long_chain=max(L, R.LONG_CHAIN))
    idx = np.flatnonzero(chains)
    if len(idx) == 0:
        return 0.0
    e = topo.edges[idx]
    lab = _k.union_find(topo.n_vertices, e[:, 0], e[:, 1])[e[:, 0]]
    _, g = np.unique(lab, return_inverse=True)
    n_chains = int(g.max()) + 1
    p, s = R._chain_stats(R._side_adjacency(topo, cre, len(N)), N, topo.edge_faces[idx, 0],
                          topo.edge_faces[idx, 1], g, n_chains, R.PERSIST_RINGS, R.SIDE_RINGS)
    good = (np.abs(p - 1.0) <= R.PERSIST_TOL) & (s <= R.SIDE_SPREAD)
    return float(support.mean()) * float(good[g].mean())


def cad_support(topo, N: np.ndarray, support: np.ndarray, q: float, *,
                th: float = 30.0) -> float:
    """``f_ref = max(f, f_g q / Q_c)`` of the module docstring, ``q`` the mesh's
    :func:`radius_in_edges` (``f`` when switched off, or when ``f`` already reaches
    :data:`meshrepair.denoise.rules.CAD_SUPPORT`)."""
    from meshrepair.denoise.rules import CAD_SUPPORT

    f = float(support.mean())
    if not SCALE_FREE_CAD or f >= CAD_SUPPORT or not q > Q_CAD:
        return f
    return max(f, crease_like_share(topo, N, support, th=th) * float(q) / Q_CAD)


# the scale-free stop of rule 1 only where the probe already reads a crease
GATED_STOP = True
GATE_SUPPORT = 0.0  # continue when f = |C| / n_E at the relative stop exceeds this


def two_phase(q: float) -> bool:
    """Whether the probe of a mesh with radius ``q`` (edge lengths) runs in two phases
    (:func:`gated_probe`): rule 1 on, the gate on and ``q > Q_0`` (below it both stops
    coincide)."""
    return bool(SCALE_FREE_STOP and GATED_STOP and q > Q_REF)


def continue_probe(support: float) -> bool:
    """The gate of :func:`gated_probe`: the probe stopped at the relative tolerance goes on to the
    scale-free one only when its crease-supported region C is not empty there,
    ``f = |C| / n_E > GATE_SUPPORT`` (a supported crease chain already read)."""
    return bool(support > GATE_SUPPORT)


def gated_probe(solver_cls, options_cls, F, n_vertices, topo, stage, kw, Vd, Vi, q, th, *,
                callback=None):
    """The two-phase probe of a mesh of radius ``q`` (edge lengths); phase 2 *continues*
    phase 1's run.

    Phase 1 stops at the relative tolerance ``τ_1 = stage.switch_tol``; when
    :func:`continue_probe` reads a crease-supported region on its normals, the same solver
    resumes phase 1's full state (vertices, normals, multipliers ρ_1 ρ_2, penalties, mask,
    normalisation, inner step, counters: :class:`meshrepair.model.solver.state.ADMMState`) with rule
    1's tolerance ``τ_2 = kw['tol']`` (``switch_tol · Q_0 / q``). Since the stop only reads
    ``rel`` and ``τ_2 < τ_1``, phase 1 + phase 2 are the iterates of one run to ``τ_2``
    (:mod:`meshrepair.model.solver.state`): the two phases of a crease-supported mesh give the
    scale-free probe, the others keep the relative stop. Returns the last phase's result, its
    ``iterations`` the whole run's, with ``probe_phases`` (1 or 2) and ``probe_gate_support``
    (f at phase 1). When phase 2 does not run, the result also carries ``crease_support``, the
    ``crease_network.supported`` read of its normals, so the caller does not compute it again.
    ``callback`` is called with each iteration entry of both phases.
    """
    import logging

    from meshrepair.denoise import crease_network as _cn

    solver = solver_cls(F, n_vertices, options=options_cls(
        stages=(stage,), **{**kw, "tol": float(stage.switch_tol)}), topo=topo)
    r = solver.solve(Vd, Vi, keep_state=True, callback=callback)
    state, r.state = r.state, None
    r.probe_phases, r.probe_gate_support = 1, float("nan")
    if r.iterations >= int(stage.max_iter) or r.stop_reason in ("callback", "interrupted"):
        return r
    r.crease_support = _cn.supported(topo, r.N, th=th)  # phase 1's (support, network)
    f = float(r.crease_support[0].mean())
    r.probe_gate_support = f
    logging.getLogger(__name__).info("probe phase 1 (q %.1f): %d iterations, support %.4f",
                                     q, r.iterations, f)
    if not continue_probe(f):
        return r
    del r
    r2 = solver.resume(state, tol=float(kw["tol"]), callback=callback)
    r2.probe_phases, r2.probe_gate_support = 2, f
    return r2
