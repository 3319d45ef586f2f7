"""The ADMM loop (17)-(21) for energy (6): :class:`ADMMSolver` on a fixed connectivity, its
sharp-edge masks M_E of (5), and rule (35) ending the last stage (see
:mod:`meshrepair.model.solver`).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np

import meshrepair.model._fused as _fused
from meshrepair import _kernels as _k
from meshrepair._kernels.fidelity import anchor_support, tangential_anchor_on
from meshrepair._kernels.priors import lengths_reg_energy_mixed
from meshrepair._kernels.tstep import t_from_normals
from meshrepair._kernels.weighted import lengths_reg_energy_weighted, t_from_normals_weighted
from meshrepair.mesh.topology import Topology, cached, edge_topology
from meshrepair.model._memory import heap_allocations
from meshrepair.model.fidelity import prox_group_l1
from meshrepair.model.inner import InnerState, VSubproblem, run_inner
from meshrepair.model.linear import NormalSystem, solve_normals
from meshrepair.model.penalties import mc_penalty
from meshrepair.model.relax import TangentialRelaxer
from meshrepair.model.solver.options import SolverOptions
from meshrepair.model.solver.result import SolverResult, StopRequested
from meshrepair.model.solver.state import ADMMState

log = logging.getLogger(__name__)


def _interior_edges(topo: Topology):
    """The interior edges ``ie``, their vertices, their two faces ``fa < fb`` and the face
    neighbour table of the N-subproblem (:class:`~meshrepair.model.linear.NormalSystem`)."""
    ie, E_int, fa, fb = _k.interior_edges(topo.edges, topo.edge_faces)
    if int(topo.edge_counts.max(initial=0)) <= 2:  # per face from its edges
        return ie, E_int, fa, fb, _k.face_neighbours(topo.face_edges, topo.edge_faces)
    return ie, E_int, fa, fb, _k.face_neighbour_table(fa, fb, topo.n_faces)


def _drop_short_chains(mask: np.ndarray, topo: Topology, min_edges: int) -> np.ndarray:
    """Unset the edges of ``mask`` whose connected sharp-edge component has < ``min_edges``."""
    idx = np.flatnonzero(mask)
    if len(idx) == 0:
        return mask
    e = topo.edges[idx]
    lab = _k.union_find(topo.n_vertices, e[:, 0], e[:, 1])
    cnt = np.bincount(lab[e[:, 0]], minlength=int(lab.max()) + 1)
    out = mask.copy()
    out[idx[cnt[lab[e[:, 0]]] < min_edges]] = False
    return out



class ADMMSolver:
    """Stateful ADMM solver for (6) on a fixed connectivity.

    Parameters
    ----------
    F : (nF, 3) int
    n_vertices : int
    M_V : (nV,) float, fidelity mask (1 keep close to V0, 0 free: the region S_D).
    edge_force : (nE,) int, optional
        Per-edge override of M_E aligned with ``self.topo.edges``: -1 free (the stage decides),
        0 always smooth (Willmore), 1 always sharp (MC).
    fixed : (nV,) bool, optional, vertices that never move.
    flat_edges : (nE,) bool, optional, the edges of the flat-TV class (stages with ``flat_a``).
    anchor : (nV,) float in [0, 1], optional, weight of the tangential anchor
        (:func:`meshrepair.model.fidelity.tangential_anchor`) applied after every V-step.
    willmore_edges : (nE,) float > 0, optional, per-edge weight of edge-Willmore replacing
        ``options.willmore_weight`` (:mod:`meshrepair.model.priors`).
    options : SolverOptions
    topo : Topology, optional (precomputed)
    """

    def __init__(self, F: np.ndarray, n_vertices: int, *, M_V: np.ndarray | None = None,
                 edge_force: np.ndarray | None = None, fixed: np.ndarray | None = None,
                 options: SolverOptions | None = None, topo: Topology | None = None,
                 flat_edges: np.ndarray | None = None, anchor: np.ndarray | None = None,
                 willmore_edges: np.ndarray | None = None):
        self.options = options or SolverOptions()
        self.options.validate()
        self.F = np.asarray(F, dtype=np.int64)
        self.topo = topo if topo is not None else edge_topology(self.F, n_vertices)
        nV = self.topo.n_vertices
        self.M_V = np.ones(nV) if M_V is None else np.asarray(M_V, dtype=np.float64)
        self.edge_force = (np.full(self.topo.n_edges, -1, np.int8) if edge_force is None
                           else np.asarray(edge_force, dtype=np.int8))
        self.fixed = None if fixed is None else np.asarray(fixed, dtype=bool)
        self.flat_edges = None if flat_edges is None else np.asarray(flat_edges, dtype=bool)
        self.anchor = (None if anchor is None or not np.any(anchor)
                       else np.asarray(anchor, dtype=np.float64))
        # the faces and vertices the anchor reads (a pure speed-up: same values)
        self._anchor_support = (None if self.anchor is None
                                else anchor_support(self.F, self.anchor))
        self.vsub = VSubproblem(self.F, nV, fixed=self.fixed)
        self._relaxer: TangentialRelaxer | None = None  # built on first use (stage.relax > 0)
        # only interior edges carry a normal jump: t, rho1 live on them
        # (built once per topology: the probe and the main solve share them; read-only)
        self.ie, self.E_int, self.fa, self.fb, table = cached(
            self.topo, ("interior_edges",), lambda: _interior_edges(self.topo))
        self.nsys = NormalSystem(self.fa, self.fb, self.topo.n_faces, table=table)
        self._flat_int = (None if self.flat_edges is None or not self.flat_edges.any()
                          else self.flat_edges[self.ie])
        self.willmore_edges = (None if willmore_edges is None
                               else np.asarray(willmore_edges, dtype=np.float64))
        if self.willmore_edges is not None and (
                self.willmore_edges.shape != (self.topo.n_edges,)
                or not np.all(np.isfinite(self.willmore_edges))
                or np.any(self.willmore_edges < 0)):
            from meshrepair.errors import MeshRepairError

            raise MeshRepairError("willmore_edges must be one finite weight >= 0 per edge")
        self._w_int = (None if self.willmore_edges is None
                       else np.ascontiguousarray(self.willmore_edges[self.ie]))

    @property
    def relaxer(self) -> TangentialRelaxer:
        """The tangential relaxation operator (built on first use)."""
        if self._relaxer is None:
            self._relaxer = TangentialRelaxer(self.topo, self.fixed)
        return self._relaxer

    # -- masks ---------------------------------------------------------------------------------
    def _mask(self, mode: str, normals: np.ndarray, given: np.ndarray | None) -> np.ndarray:
        nE = self.topo.n_edges
        if mode == "all":
            m = self.topo.interior.copy()
        elif mode == "none":
            m = np.zeros(nE, bool)
        elif mode == "given":
            m = np.zeros(nE, bool) if given is None else np.asarray(given, bool).copy()
        else:  # the dihedral threshold (5) on interior edges
            m = np.zeros(nE, bool)
            m[self.ie] = _k.creased(normals, self.fa, self.fb, self.options.th)
            if self.options.min_feature_edges > 1:
                m = _drop_short_chains(m, self.topo, self.options.min_feature_edges)
        m[self.edge_force == 0] = False
        m[self.edge_force == 1] = True
        return m

    def energy(self, V: np.ndarray, V0: np.ndarray, sharp: np.ndarray, a: float) -> float:
        """Energy (6) at ``V`` (normalised units) for mask ``sharp`` (per edge) and ``a``."""
        o = self.options
        Nv = _k.face_normals(V, self.F)
        t = _k.grad_edges(Nv, _k.edge_lengths(V, self.E_int), self.fa, self.fb)
        nt = np.sqrt(np.einsum("ij,ij->i", t, t))
        sh = sharp[self.ie]
        reg = np.where(sh, mc_penalty(nt, a), o.willmore_weight * nt**2).sum()
        d = V - V0
        fid = 0.5 * o.lam * float(np.einsum("i,ij,ij->", self.M_V**2, d, d))
        return float(reg + fid)

    # -- main loop -----------------------------------------------------------------------------
    def solve(self, V0: np.ndarray, V_init: np.ndarray | None = None, *,
              given_mask: np.ndarray | None = None,
              callback: Callable[[dict], None] | None = None,
              keep_state: bool = False) -> SolverResult:
        """Run the schedule from ``V_init`` (default ``V0``) with data ``V0``.

        Parameters
        ----------
        V0 : (nV, 3) data of the fidelity term.
        V_init : (nV, 3), optional initial mesh (e.g. with a filled hole).
        given_mask : (nE,) bool, M_E for stages whose mask is ``"given"``.
        callback : called with each history entry; raise :class:`StopRequested` to stop.
        keep_state : hand the loop's :class:`~meshrepair.model.solver.state.ADMMState` back as
            ``result.state``, so that :meth:`resume` can continue the same run.

        Returns
        -------
        SolverResult
        """
        with heap_allocations():
            st = self._start(V0, V_init, given_mask)
            return self._run(st, self.options.tol, callback, keep_state)

    def resume(self, state: ADMMState, *, tol: float | None = None,
               callback: Callable[[dict], None] | None = None,
               keep_state: bool = False) -> SolverResult:
        """Continue the run whose ``result.state`` is ``state`` (from :meth:`solve` or
        :meth:`resume` of this solver, with ``keep_state=True``) until rule (35) with ``tol``
        (default ``options.tol``) or the schedule's ``max_iter``.

        Phase 1 stopped by ``rel < τ_1`` and resumed with ``τ_2 < τ_1`` gives the iterates of
        one run with ``τ_2`` (:mod:`meshrepair.model.solver.state`). ``state`` is advanced in place;
        the result's ``iterations`` and ``history`` count the whole run.
        """
        if len(state.V) != self.topo.n_vertices or len(state.N) != self.topo.n_faces:
            from meshrepair.errors import MeshRepairError

            raise MeshRepairError("resume: the state is not of this solver's mesh")
        t = self.options.tol if tol is None else float(tol)
        if not (np.isfinite(t) and t > 0):
            from meshrepair.errors import MeshRepairError

            raise MeshRepairError(f"resume: tol must be finite and > 0, got {tol!r}")
        with heap_allocations():
            return self._run(state, t, callback, keep_state)

    def _start(self, V0: np.ndarray, V_init: np.ndarray | None,
               given_mask: np.ndarray | None) -> ADMMState:
        """The state before the first iteration: normalisation, normals, zero multipliers."""
        o = self.options
        topo = self.topo
        V0 = np.asarray(V0, dtype=np.float64)
        Vi = V0 if V_init is None else np.asarray(V_init, dtype=np.float64)
        used = np.zeros(topo.n_vertices, bool)
        used[self.F.ravel()] = True
        center = (Vi if used.all() else Vi[used]).mean(axis=0)  # (same rows, same sums)
        scale = float(_k.edge_lengths(Vi, topo.edges).mean())
        if not scale > 0:
            from meshrepair.errors import MeshRepairError

            raise MeshRepairError("all edges have zero length; the mesh has no extent")
        X0 = np.ascontiguousarray((V0 - center) / scale)
        V = np.ascontiguousarray((Vi - center) / scale)
        N = _k.face_normals(V, self.F)
        return ADMMState(
            center=center, scale=scale, X0=X0, fid=o.lam * self.M_V**2, V=V, N=N, Nv=N.copy(),
            l=_k.edge_lengths(V, self.E_int), rho1=np.zeros((len(self.ie), 3)),
            rho2=np.zeros((topo.n_faces, 3)),
            inner=InnerState(step=1.0 if o.precondition else 1e-2, precondition=o.precondition),
            given_mask=given_mask, sharp=np.zeros(topo.n_edges, bool))

    def _run(self, s: ADMMState, tol: float, callback: Callable[[dict], None] | None,
             keep_state: bool) -> SolverResult:
        o = self.options
        topo = self.topo
        F, X0, fid, given_mask = self.F, s.X0, s.fid, s.given_mask
        fa, fb, E_int, nF = self.fa, self.fb, self.E_int, topo.n_faces
        V, N, Nv, l, rho1, rho2 = s.V, s.N, s.Nv, s.l, s.rho1, s.rho2
        state, history = s.inner, s.history
        t_start = time.perf_counter() - s.elapsed
        k = s.k
        stop_reason = "max_iter"
        sharp = s.sharp
        beta1, beta2 = s.beta1, s.beta2
        try:
            while s.stage < len(o.stages):
                si = s.stage
                stage = o.stages[si]
                last = si == len(o.stages) - 1
                if not s.begun:
                    src = N if o.mask_source == "N" else _k.face_normals(V, F)
                    sharp = self._mask(stage.mask, src, given_mask)
                    beta1 = stage.beta1 if (sharp.any() or stage.mask == "all") else max(
                        stage.beta1, stage.eps * 2.0 * o.willmore_weight)
                    if sharp.any() and beta1 <= stage.a:
                        beta1 = 1.01 * stage.a
                    beta2 = stage.beta2_ratio * beta1
                    s.sharp, s.beta1, s.beta2, s.begun, s.j = sharp, beta1, beta2, True, 0
                    log.info("stage %s: a=%g beta1=%g beta2=%g sharp edges %d/%d", stage.name,
                             stage.a, beta1, beta2, int(sharp.sum()), topo.n_edges)
                sh = sharp[self.ie]  # the mask on interior edges, re-gathered when it changes
                done = False  # rule (35) met in the last stage: the run stops in this stage
                for j in range(s.j, stage.max_iter):
                    if (stage.mask == "adaptive" and o.mask_update_every and j > 0
                            and j % o.mask_update_every == 0):
                        src = N if o.mask_source == "N" else _k.face_normals(V, F)
                        sharp = self._mask("adaptive", src, given_mask)
                        sh = sharp[self.ie]
                    # (17) t-update from N (t_update / t_update_mixed on D N, one edge pass)
                    mixed = stage.flat_a > 0 and self._flat_int is not None
                    w_int = self._w_int if stage.willmore_edges else None
                    if w_int is not None:  # per-edge Willmore weights: D N and the prox
                        fl = self._flat_int if mixed else None  # in one pass (same values)
                        t = t_from_normals_weighted(N, l, fa, fb, rho1, sh, fl, a=stage.a,
                                                    a_flat=stage.flat_a,
                                                    beta1=max(beta1, 1.01 * stage.flat_a),
                                                    w=w_int)
                    elif mixed:
                        fl = self._flat_int
                        t = t_from_normals(N, l, fa, fb, rho1, sh, fl, a=stage.a,
                                           a_flat=stage.flat_a,
                                           beta1=max(beta1, 1.01 * stage.flat_a),
                                           w=o.willmore_weight)
                    else:
                        t = t_from_normals(N, l, fa, fb, rho1, sh, a=stage.a, beta1=beta1,
                                           w=o.willmore_weight)
                    # (18) N-update via (25), then normalise
                    c = beta2 / beta1
                    B = _k.rhs(c, Nv, rho2, beta1, t, rho1, l, fa, fb)
                    if o.n_solver == "direct":
                        N, _ = solve_normals(self.nsys.matrix(l * l, c), B, N, method="direct")
                    else:
                        N, _ = self.nsys.solve_cg(l * l, c, B, N, rtol=o.n_rtol)
                    N, z = _k.normalize_z(N, Nv, rho2, beta2)
                    # (19) V-update: inner solver on (26), warm-started
                    if o.huber_delta > 0:  # outlier offsets S: prox of δ||.||, fidelity.py
                        S = prox_group_l1(V - X0, o.huber_delta)
                        Xd = X0 + S
                    else:
                        Xd = X0
                    self.vsub.set(Xd, fid, z)
                    Vn = run_inner(o.inner_solver, self.vsub, V, o.inner_iters, state)
                    if self.anchor is not None:
                        Vn = tangential_anchor_on(Vn, X0, F, self.anchor,
                                                  self._anchor_support)
                    if stage.relax > 0:
                        Vn = self.relaxer.step(Vn, sharp, stage.relax)
                    # (20)-(21) multipliers (D with the lengths of V^(k), as in the N-update)
                    res_t = _k.update_rho1(t, N, l, fa, fb, rho1, beta1)
                    Nv, res_n = _fused.normals_update_rho2(Vn, F, N, rho2, beta2)
                    rel = _fused.rel_change(Vn, V)
                    if not np.isfinite(rel):  # NaN or inf anywhere in V^(k+1)
                        self._not_finite(o.inner_solver, k + 1)
                    V = Vn
                    k += 1
                    if mixed and w_int is not None:  # the two passes below in one
                        l, reg, extra = lengths_reg_energy_weighted(
                            V, E_int, Nv, fa, fb, sh, fl, stage.a, stage.flat_a,
                            o.willmore_weight, w_int)
                        reg += extra
                    elif mixed:  # flat-TV edges: the MC value of flat_a instead of Willmore
                        l, reg = lengths_reg_energy_mixed(V, E_int, Nv, fa, fb, sh, fl, stage.a,
                                                          stage.flat_a, o.willmore_weight)
                    else:
                        l, reg = _fused.lengths_reg_energy(V, E_int, Nv, fa, fb, sh, stage.a,
                                                           o.willmore_weight)
                    if w_int is not None and not mixed:  # per-edge Willmore weights
                        reg += _fused.willmore_extra(l, Nv, fa, fb, w_int, o.willmore_weight,
                                                     sh)
                    entry = {
                        "iter": k,
                        "stage": stage.name,
                        "energy": reg + 0.5 * _k.sqdist(V, Xd, fid) + (
                            o.huber_delta * float(fid @ np.linalg.norm(Xd - X0, axis=1))
                            if o.huber_delta > 0 else 0.0),
                        "rel_change": float(rel),
                        "res_t": float(np.sqrt(res_t / max(len(fa), 1))),
                        "res_N": float(np.sqrt(res_n / nF)),
                        "n_sharp": int(sharp.sum()),
                        "time": time.perf_counter() - t_start,
                    }
                    history.append(entry)
                    s.V, s.N, s.Nv, s.l, s.sharp, s.k, s.j = V, N, Nv, l, sharp, k, j + 1
                    s.elapsed = entry["time"]
                    if callback is not None:
                        callback(entry)
                    if j + 1 >= stage.min_iter:
                        if last and rel < tol:
                            stop_reason = "rule (35)"
                            done = True
                            break
                        if not last and rel < stage.switch_tol:
                            break
                if done:
                    break
                s.stage, s.begun = si + 1, False  # the stage ended: the next one starts
        except (StopRequested, KeyboardInterrupt) as exc:
            stop_reason = "interrupted" if isinstance(exc, KeyboardInterrupt) else "callback"
            log.warning("solver stopped by %s after %d iterations", stop_reason, k)
        scale, center = s.scale, s.center
        return SolverResult(
            V=V * scale + center,
            F=self.F.copy(),
            N=N,
            M_E=sharp,
            M_V=self.M_V.copy(),
            edges=topo.edges.copy(),
            history=history,
            iterations=k,
            stop_reason=stop_reason,
            scale=scale,
            state=s if keep_state else None,
        )

    @staticmethod
    def _not_finite(inner_solver: str, k: int) -> None:
        """Refuse an iterate with non-finite coordinates (the run cannot continue from it)."""
        from meshrepair.errors import MeshRepairError

        raise MeshRepairError(
            f"the V-update (26) of ADMM iteration {k} gave non-finite vertex coordinates "
            f"(inner solver {inner_solver!r}); the mesh may have degenerate (zero-area) faces: "
            f"remove them, or use the default inner_solver='armijo'")

    def with_options(self, **changes) -> ADMMSolver:
        """A solver on the same connectivity with some options changed (reuses the topology)."""
        return ADMMSolver(self.F, self.topo.n_vertices, M_V=self.M_V, edge_force=self.edge_force,
                          fixed=self.fixed, options=replace(self.options, **changes),
                          topo=self.topo, flat_edges=self.flat_edges, anchor=self.anchor,
                          willmore_edges=self.willmore_edges)
