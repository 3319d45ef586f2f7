"""The V-subproblem (26) and its inner solvers.

.. math::
    \\mathcal J_V(V) = \\frac{\\lambda}{2}\\sum_i (M_V)_i \\|V_i - V^0_i\\|^2
        + \\sum_m \\langle \\rho_{2m} - \\beta_2 N_m, \\mathcal N_m(V)\\rangle \\; (+\\text{const})

(the ``β2/2 ||N_m - 𝒩_m(V)||²`` term equals ``β2 - β2 <N_m, 𝒩_m(V)>`` for unit vectors). Its
gradient is (28). All inner solvers share :class:`VSubproblem`'s energy-and-gradient kernel and are
warm-started from the previous ADMM iterate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

import meshrepair.model._fused as _fused
from meshrepair import _kernels as _k
from meshrepair._kernels.select import median  # np.median's value by one selection

STIFF_RATIO = 30.0  # vertices stiffer than this many times the median get a smaller step
INNER_SOLVERS = ("armijo", "gd", "heavy_ball", "lbfgs", "bfgs")
BFGS_MAX_VERTICES = 400
"""Largest mesh ``inner_solver='bfgs'`` accepts: scipy's BFGS keeps a dense (3 nV)² inverse
Hessian and updates it with dense (3 nV)³ products every iteration (at 500 vertices a denoise
takes minutes); 'lbfgs' is the solver for larger meshes."""


class VSubproblem:
    """Energy and gradient of (26) for a fixed connectivity.

    Parameters
    ----------
    F : (nF, 3) int64
    n_vertices : int
    fixed : (nV,) bool, optional
        Vertices that do not move (their gradient is zeroed).
    """

    def __init__(self, F: np.ndarray, n_vertices: int, fixed: np.ndarray | None = None):
        self.F = np.asarray(F, dtype=np.int64)
        nF = len(self.F)
        self.nV = int(n_vertices)
        self.S = None
        if not _k.HAVE_NUMBA:  # corner k of face m -> column k*nF + m, for the numpy scatter
            cols = np.arange(3 * nF)
            rows = self.F.T.ravel()
            self.S = sp.csr_matrix((np.ones(3 * nF), (rows, cols)), shape=(self.nV, 3 * nF))
        self.free = None if fixed is None or not np.any(fixed) else ~np.asarray(fixed, bool)
        self.V0 = np.zeros((self.nV, 3))
        self.wfid = np.zeros(self.nV)
        self.z = np.zeros((nF, 3))
        self.n_energy = 0
        self.n_grad = 0

    def set(self, V0: np.ndarray, fidelity: np.ndarray, z: np.ndarray) -> None:
        """Set ``V0``, the per-vertex fidelity weights ``λ (M_V)_i²`` and ``z = ρ2 - β2 N``."""
        self.V0 = V0
        self.wfid = fidelity
        self.z = z

    def energy(self, V: np.ndarray) -> float:
        """``J_V(V)`` up to a constant."""
        self.n_energy += 1
        return _k.venergy(V, self.F, self.z, self.V0, self.wfid)

    def energy_grad(self, V: np.ndarray) -> tuple[float, np.ndarray]:
        """``(J_V(V), ∇J_V(V))`` with the gradient (28), shape ``(nV, 3)``."""
        self.n_energy += 1
        self.n_grad += 1
        e, grad = _k.venergy_grad(V, self.F, self.z, self.V0, self.wfid, self.S)
        if self.free is not None:
            grad[~self.free] = 0.0
        return e, grad


    def energy_grad_scale(self, V: np.ndarray) -> tuple[float, np.ndarray, np.ndarray, float]:
        """``(J_V, ∇J_V, h, h_min)`` in one face pass: the diagonal scale of :meth:`diag_scale`
        is ``max(h, h_min)`` (left unclamped here so one fused pass can apply it)."""
        self.n_energy += 1
        self.n_grad += 1
        e, grad, h = _fused.venergy_grad_hdiag(V, self.F, self.z, self.V0, self.wfid, self.S)
        if self.free is not None:
            grad[~self.free] = 0.0
        return e, grad, h, max(STIFF_RATIO * median(h), 1e-300)

    def energy_at(self, V: np.ndarray, d: np.ndarray, step: float, out: np.ndarray) -> float:
        """Write ``V + step d`` into ``out`` and return ``J_V`` there (one fused pass)."""
        self.n_energy += 1
        return _fused.venergy_trial(V, d, step, out, self.F, self.z, self.V0, self.wfid)

    def energy_grad_at(self, V: np.ndarray, d: np.ndarray, step: float, out: np.ndarray
                       ) -> tuple[float, np.ndarray]:
        """Write ``V + step d`` into ``out`` and return ``(J_V, ∇J_V)`` there (one fused pass;
        the values of :meth:`energy_grad` at ``out``)."""
        self.n_energy += 1
        self.n_grad += 1
        e, grad = _fused.venergy_grad_trial(V, d, step, out, self.F, self.z, self.V0, self.wfid,
                                            self.S)
        if self.free is not None:
            grad[~self.free] = 0.0
        return e, grad

    def diag_scale(self, V: np.ndarray) -> np.ndarray:
        """Per-vertex diagonal scale of the Hessian of (26) at ``V`` (see ``vhess_diag``)."""
        h = _k.vhess_diag(V, self.F, self.z, self.wfid)
        # only vertices stiffer than the typical one are slowed down: on a regular mesh this is
        # plain gradient descent, and slivers no longer dictate the step of everyone else
        return np.maximum(h, max(STIFF_RATIO * median(h), 1e-300))


@dataclass
class InnerState:
    """What an inner solver remembers between ADMM iterations (the last accepted step)."""

    step: float = 1e-2
    precondition: bool = False


def _armijo_line(prob: VSubproblem, V, E, g, d, slope, step, c1=1e-4, shrink=0.5):
    """Backtrack along direction ``d`` (``slope = <g, d> < 0``) until (31) holds."""
    while step > 1e-14:
        Vn = V + step * d
        En = prob.energy(Vn)
        if En <= E + c1 * step * slope:
            return Vn, En, step
        step *= shrink
    return V, E, 0.0


def solve_armijo(prob: VSubproblem, V: np.ndarray, iters: int, state: InnerState) -> np.ndarray:
    """Gradient descent with Armijo backtracking (31), starting from twice the last step.

    With ``state.precondition`` the direction is ``-D⁻¹ ∇J`` with the diagonal scale of
    :meth:`VSubproblem.diag_scale` (computed once per call), and (31) uses the slope
    ``<∇J, d>``; the step is then dimensionless (≈ 1 for a well-scaled problem).

    The preconditioned path runs on fused passes (:mod:`meshrepair.model._fused`): the scale comes
    with the first gradient, the direction and its slope in one vertex pass, and each trial point
    is written into one of two reused buffers while its energy is evaluated (``V`` itself is never
    written). A trial after a rejected one (usually accepted) also evaluates the gradient in its
    pass (:meth:`VSubproblem.energy_grad_at`), which saves the separate gradient pass after
    acceptance. The iterates are those of the unfused loop (that trial's energy comes from the
    gradient kernel, which rounds differently from the energy kernel: a test within rounding of
    its threshold could go the other way).
    """
    if not state.precondition:
        return _solve_armijo_plain(prob, V, iters, state)
    E, g, h, h_min = prob.energy_grad_scale(V)
    step = state.step * 2.0
    d = np.empty_like(V)
    bufs = [np.empty_like(V), np.empty_like(V)]
    c1, shrink = 1e-4, 0.5
    for it in range(iters):
        gg = _fused.descent_direction(g, h, h_min, d)
        if gg == 0.0:
            break
        out = bufs[it % 2]
        need_grad = it + 1 < iters
        rejected = False
        g_out = None
        while step > 1e-14:  # (31) along d, slope -gg
            if need_grad and rejected:
                # after a rejected trial the next one is usually accepted: its gradient, needed
                # next, comes from the same pass (and so does its energy, the value the next
                # iteration's test uses in any case)
                En, g_out = prob.energy_grad_at(V, d, step, out)
            else:
                En = prob.energy_at(V, d, step, out)
            if En <= E + c1 * step * -gg:
                break
            step *= shrink
            rejected = True
        else:
            step = state.step
            break
        V, E = out, En
        state.step = step
        if need_grad:
            if g_out is not None:
                g = g_out
            else:
                E, g = prob.energy_grad(V)
            step *= 2.0
    return V


def _solve_armijo_plain(prob: VSubproblem, V: np.ndarray, iters: int, state: InnerState
                        ) -> np.ndarray:
    """:func:`solve_armijo` without the preconditioner (direction ``-∇J``)."""
    E, g = prob.energy_grad(V)
    step = state.step * 2.0
    for it in range(iters):
        d = -g
        gg = -float(np.einsum("ij,ij->", g, d))
        if gg == 0.0:
            break
        V, E, step = _armijo_line(prob, V, E, g, d, -gg, step)
        if step == 0.0:
            step = state.step
            break
        state.step = step
        if it + 1 < iters:
            E, g = prob.energy_grad(V)
            step *= 2.0
    return V


def solve_gd(prob: VSubproblem, V: np.ndarray, iters: int, state: InnerState,
             step: float | None = None) -> np.ndarray:
    """Gradient descent with a fixed step (``state.step`` unless given), safeguarded.

    The step stays fixed while it lowers ``J_V``; a step that would raise ``J_V`` or leave the
    finite numbers is halved (and kept halved) until it lowers ``J_V``, so that a step too large
    for the problem's curvature (``α > 2 / L``) cannot make the iterates diverge. Below
    ``1e-14`` the solver stops at the last accepted point (no step lowers ``J_V`` along
    ``-∇J_V``). The last accepted step is handed back in ``state.step`` for the next call.
    """
    alpha = state.step if step is None else step
    E, g = prob.energy_grad(V)
    for _ in range(iters):
        while alpha > 1e-14:
            Vn = V - alpha * g
            En, gn = prob.energy_grad(Vn)
            if En <= E and np.isfinite(En):  # False for NaN
                break
            alpha *= 0.5
        else:
            break
        V, E, g = Vn, En, gn
        if step is None:
            state.step = alpha
    return V


def solve_heavy_ball(prob: VSubproblem, V: np.ndarray, iters: int, state: InnerState,
                     delta: float = 0.5) -> np.ndarray:
    """Heavy-ball iteration (27) with backtracking on the step (the momentum term is kept when
    the combined direction descends, dropped otherwise)."""
    E, g = prob.energy_grad(V)
    Vprev = V.copy()
    step = state.step * 2.0
    for it in range(iters):
        d = -g + (delta / max(step, 1e-300)) * (V - Vprev)
        slope = float(np.einsum("ij,ij->", g, d))
        if slope >= 0:
            d = -g
            slope = -float(np.einsum("ij,ij->", g, g))
        if slope == 0.0:
            break
        Vn, En, s = _armijo_line(prob, V, E, g, d, slope, step)
        if s == 0.0:
            break
        Vprev, V, E = V, Vn, En
        state.step = step = s
        if it + 1 < iters:
            E, g = prob.energy_grad(V)
            step *= 2.0
    return V


def solve_lbfgs(prob: VSubproblem, V: np.ndarray, iters: int, state: InnerState,
                method: str = "L-BFGS-B") -> np.ndarray:
    """(L-)BFGS from scipy on the flattened coordinates, warm-started at ``V``."""
    from scipy.optimize import minimize

    shape = V.shape

    def fun(x):
        e, g = prob.energy_grad(x.reshape(shape))
        return e, g.ravel()

    opts = {"maxiter": iters, "gtol": 1e-9}
    if method == "L-BFGS-B":
        opts["ftol"] = 1e-15
    res = minimize(fun, V.ravel(), jac=True, method=method, options=opts)
    X = res.x.reshape(shape)
    if not np.all(np.isfinite(X)):  # a line search that left the finite numbers: no progress
        return V
    return X


def run_inner(name: str, prob: VSubproblem, V: np.ndarray, iters: int, state: InnerState
              ) -> np.ndarray:
    """Dispatch to the inner solver ``name`` (one of :data:`INNER_SOLVERS`)."""
    if name == "armijo":
        return solve_armijo(prob, V, iters, state)
    if name == "gd":
        return solve_gd(prob, V, iters, state)
    if name == "heavy_ball":
        return solve_heavy_ball(prob, V, iters, state)
    if name == "lbfgs":
        return solve_lbfgs(prob, V, iters, state)
    if name == "bfgs":
        if len(V) > BFGS_MAX_VERTICES:
            from meshrepair.errors import MeshRepairError

            mb = (V.size ** 2) * 8 / 2**20
            raise MeshRepairError(
                f"inner_solver='bfgs' stores a dense (3·{len(V)})² inverse Hessian ({mb:.0f} MB) "
                f"and updates it with dense products every iteration; use inner_solver='lbfgs' "
                f"for meshes with more than {BFGS_MAX_VERTICES} vertices")
        return solve_lbfgs(prob, V, iters, state, method="BFGS")
    from meshrepair.errors import MeshRepairError

    raise MeshRepairError(f"unknown inner solver {name!r}; choose one of {INNER_SOLVERS}")
