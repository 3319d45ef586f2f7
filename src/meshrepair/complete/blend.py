"""Blending the seam of a completed mesh: the masks of energy (6) on strip(b0) and the solve.

``S_D = strip(b0)`` is the set of vertices within ``strip_rings`` edge rings of the seam, on both
sides. The fidelity mask ``M_V`` is 1 outside it; on it the paper sets 0. In ``"adaptive"`` mode
(the default of :func:`meshrepair.complete`) we use a *gap-adaptive* fidelity instead
(:func:`_strip_fidelity`): ``M_V = w max(0, 1 - g / GAP_FREE)`` with ``g`` the largest normal
seam gap (mean edge lengths) among the seam vertices within ``strip_rings`` rings. Where the
template already meets the mesh there is nothing to hide and the stitched surface ``V^(0)`` is
kept (with ``M_V = 0`` the edge-Willmore energy fairs even an exact template away from the truth,
by about 0.1 l after 80 iterations); where the seam is open the strip is free.
``M_E`` on strip edges is forced smooth, sharp or left to the dihedral threshold (``mode``).
With ``fix_outside`` the solve runs on the band of ``strip_rings + 2`` rings around the seam.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from meshrepair.complete.stitch import _rings
from meshrepair.mesh.geometry import face_normals, sharp_edge_mask
from meshrepair.mesh.topology import Topology, edge_topology, vertex_adjacency
from meshrepair.model.solver import ADMMSolver, SolverOptions, Stage

__all__ = ["GAP_FREE", "BlendResult", "blend_seam"]

#: normal seam gap (mean edge lengths) at which the strip becomes fully free
GAP_FREE = 0.25
_EDGE_FORCE = {"smooth": 0, "sharp": 1, "adaptive": -1}


@dataclass
class BlendResult:
    """Result of :func:`blend_seam` (see :class:`meshrepair.complete.api.CompletionResult`)."""

    V: np.ndarray
    M_V: np.ndarray
    M_E: np.ndarray
    topo: Topology
    edge_force: np.ndarray
    strip: np.ndarray
    fixed: np.ndarray
    lam: float
    history: list = field(default_factory=list)
    iterations: int = 0
    stop_reason: str = ""


def _strip_fidelity(topo, seam: np.ndarray, gap_l: np.ndarray, strip: np.ndarray,
                    strip_rings: int, weight: float) -> np.ndarray:
    """Fidelity mask ``M_V``: 1 outside the strip; on it ``weight * max(0, 1 - g / tau)``.

    ``g`` is the largest normal seam gap (mean edge lengths, before the harmonic spreading; the
    gap's component along the remaining surface's vertex normal at ``b0``) among the
    seam vertices within ``strip_rings`` rings, ``tau = GAP_FREE`` mean edge lengths: where the
    template already meets the mesh the stitched surface is kept close to ``V^(0)``, where the
    seam is open the strip is free (the paper's ``M_V = 0``).
    """
    nV = topo.n_vertices
    M_V = np.ones(nV)
    if weight <= 0:
        M_V[strip] = 0.0
        return M_V
    A = vertex_adjacency(topo.edges, nV).tocsr()
    g = np.zeros(nV)
    g[seam] = gap_l
    for _ in range(int(strip_rings)):
        g_next = np.maximum(g, A.multiply(g[None, :]).max(axis=1).toarray().ravel())
        if np.array_equal(g_next, g):  # the dilation has stopped growing
            break
        g = g_next
    M_V[strip] = weight * np.clip(1.0 - g[strip] / GAP_FREE, 0.0, 1.0)
    return M_V


def blend_seam(V_init: np.ndarray, F_star: np.ndarray, seam: np.ndarray, gap_l: np.ndarray, *,
               strip_rings: int, mode: str, strip_fidelity: float, fix_outside: bool,
               denoise: bool, lam: float | None, th: float, a: float, iterations: int,
               mask_update_every: int, relax: float, tol: float, inner_solver: str,
               callback: Callable[[dict], None] | None) -> BlendResult:
    """Build the masks on ``strip(seam)`` and minimise energy (6) (options as in ``complete``).

    Parameters
    ----------
    V_init : (nV, 3) float64, the stitched mesh ``V^(0)``
    F_star : (nF, 3) int64
    seam : (n,) int64, the seam loop
    gap_l : (n,) float, the normal seam gap at each seam vertex, in mean edge lengths

    Returns
    -------
    BlendResult
    """
    nVs = len(V_init)
    topo = edge_topology(F_star, nVs)
    dist = _rings(topo, seam, strip_rings + 2)
    strip = dist <= strip_rings
    M_V = _strip_fidelity(topo, seam, gap_l, strip, strip_rings, strip_fidelity)
    fixed = ~strip if fix_outside else np.zeros(nVs, bool)

    def force_for(edges: np.ndarray, d: np.ndarray) -> np.ndarray:
        ef = np.full(len(edges), -1, np.int8)
        on = (d[edges[:, 0]] <= strip_rings) & (d[edges[:, 1]] <= strip_rings)
        ef[on] = _EDGE_FORCE[mode]
        return ef

    if denoise:
        from meshrepair.model.noise import estimate_noise
        from meshrepair.model.schedule import default_stages, lambda_from_noise

        stages = default_stages(feature_iters=int(iterations), a=a)
        lam_used = lambda_from_noise(estimate_noise(V_init, F_star)) if lam is None else lam
    else:
        stages = (Stage(a=a, eps=1.2, beta2_ratio=1.7, mask="adaptive", max_iter=int(iterations),
                        min_iter=int(iterations), relax=float(relax), name="blend"),)
        lam_used = 1.0 if lam is None else float(lam)
    opts = SolverOptions(lam=lam_used, th=th, stages=stages, tol=tol,
                         inner_solver=inner_solver, mask_update_every=mask_update_every)

    V_out = V_init.copy()
    M_E = sharp_edge_mask(face_normals(V_init, F_star), topo, th).astype(bool)
    edge_force = force_for(topo.edges, dist)
    history: list[dict] = []
    n_it, stop = 0, "no iterations"
    if iterations > 0 and strip.any():
        if fix_outside:
            fsel = (dist[F_star] <= strip_rings + 2).all(axis=1)
            loc = np.unique(F_star[fsel])
            g2l = np.full(nVs, -1, np.int64)
            g2l[loc] = np.arange(loc.size)
            F_loc = g2l[F_star[fsel]]
            topo_l = edge_topology(F_loc, loc.size)
            solver = ADMMSolver(F_loc, loc.size, M_V=M_V[loc],
                                edge_force=force_for(topo_l.edges, dist[loc]),
                                fixed=fixed[loc], options=opts, topo=topo_l)
            res = solver.solve(V_init[loc], V_init=V_init[loc], callback=callback)
            free = ~fixed[loc]
            V_out[loc[free]] = res.V[free]
            M_E = sharp_edge_mask(face_normals(V_out, F_star), topo, th).astype(bool)
            ge = loc[topo_l.edges]
            codes = topo.edges[:, 0] * np.int64(nVs) + topo.edges[:, 1]
            gi = np.searchsorted(codes, ge[:, 0] * np.int64(nVs) + ge[:, 1])
            M_E[gi] = res.M_E
        else:
            solver = ADMMSolver(F_star, nVs, M_V=M_V, edge_force=edge_force, fixed=fixed,
                                options=opts, topo=topo)
            res = solver.solve(V_init, V_init=V_init, callback=callback)
            V_out = res.V
            if fixed.any():
                V_out[fixed] = V_init[fixed]
            M_E = res.M_E
        history, n_it, stop = res.history, res.iterations, res.stop_reason

    return BlendResult(V=V_out, M_V=M_V, M_E=M_E, topo=topo, edge_force=edge_force, strip=strip,
                       fixed=fixed, lam=float(lam_used), history=history, iterations=n_it,
                       stop_reason=stop)
