"""Feature-aware denoising: the public one-shot function over the shared ADMM solver.

Default schedule (docs/parameters.md has the measurements behind every rule; the decisions are
recorded in ``DenoiseResult.params``):

0. *Unfold* faces folded over by noise (:func:`meshrepair.relax.untangle`). The unfolded mesh
   is the start of the solves; the fidelity data stays the input, except for impulsive noise
   (:func:`fidelity_data`). Faces still folded in the result are unfolded the same way at the
   end (:func:`unfold_result`).
1. *Probe*: the robust stage below on the whole mesh (MC with ``a = 0.5`` on every edge, a
   total-variation-like smoother of the normals). Its result N¹ decides:

   * the *crease-supported region* C (:func:`meshrepair.regions.crease_support`): long chains
     (≥ 30 edges) of edges whose N¹-dihedral exceeds ``th``, dilated by 2 rings;
   * the *flat edges* of C (:func:`meshrepair.regions.flat_edges`, probe normal spread < 7°);
   * the *noise scale* (:func:`meshrepair.scale.noise_scale`): correlation ratio ρ, length, level;
   * the *direction* of the noise (:func:`meshrepair.scale.tangential_ratio` r_t).

2. *Robust stage* from the input again: MC (``a = 0.5``, 0.25 for heavy noise γ̂ > 0.33) on C,
   edge-Willmore elsewhere; ``β1 = 2a``, ``β2 = 10 β1``; ``clip(130 γ̂, 10, 40)`` iterations
   (40 with fold-overs; ``40 + 600 (γ̂ - 0.33)`` up to 120 for heavy noise), left early when the
   relative change of V drops below ``2e-4``.
3. *Feature stage*: in C, M_E from the dihedral threshold (refreshed every 3 iterations, chains
   ≥ 6 edges) with ``a = 10``, and the flat-TV class (:mod:`meshrepair.priors`, MC ``a = 0.5``)
   on C's flat edges; edge-Willmore elsewhere, with weight ``6 w`` outside C on CAD parts
   (:func:`outside_weight`); ``β1 = 1.2 a``, ``β2 ≈ 1.67 β1``; ≤ 60 iterations or rule (35).
4. *Polish* (heavy noise on CAD parts, correlated noise; :func:`polish_rule`): a bilateral
   normal filter bounded by the converged M_E on the flat patches, at the noise's scale, then
   the vertices to the filtered normals (:mod:`meshrepair.polish`).
5. *Tangential re-anchoring* of the smooth region (:mod:`meshrepair.reproject`): outside C the
   result's vertices slide along the result surface towards the closest points of the input's
   vertices, ``V_i + w_i (π_S(V⁰_i) - V_i)`` with the least-variance weights
   ``w_i = σ²/(σ² + κ² d_i²)``, when the residual tangential ratio reads noise along the
   normals (``ρ_t < 0.6``) and the noise is not heavy (:data:`REANCHOR`).

Throughout: λ = ``clip(0.02 / γ̂², 0.05, 1)``; the Willmore weight ``w`` from ρ for correlated
noise along the normals (:func:`willmore_weight_from_scale`) and then ``3 max(1, ℓ²)`` V-steps
per iteration for its correlation length ℓ, the probe included (:func:`inner_iters_from_scale`);
a Huber fidelity for impulsive noise (:mod:`meshrepair.fidelity`); a tangential anchor on C
when the noise lies along the normals (r_t < 0.65). All parameters are in mean-edge-length
units, so the result is equivariant under rotation, translation and uniform scaling.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from ._memory import heap_allocations
from .errors import MeshRepairError
from .noise import noise_statistics
from .regions import crease_support, flat_edges
from .relax import untangle
from .scale import noise_scale, tangential_ratio
from .solver import ADMMSolver, SolverOptions, Stage

log = logging.getLogger(__name__)


@dataclass
class DenoiseResult:
    """Result of :func:`denoise`.

    Attributes
    ----------
    V : (nV, 3) float64, denoised vertices (same order as the input)
    F : (nF, 3) int64, the input connectivity
    M_E : (nE,) bool, the sharp-edge mask of the last stage
    edges : (nE, 2) int64, the edges M_E refers to
    M_V : (nV,) float64, the fidelity mask used
    history : list of dict, one per ADMM iteration (energy, rel_change, res_t, res_N, time, ...)
    iterations : int
    stop_reason : str
    noise_estimate : float, γ̂ of the input in mean edge lengths
    params : dict, the parameters actually used
    n_unfolded : int, faces folded over in the input that were unfolded before the solve
        (``params["result_folds_unfolded"]``: faces folded in the solve's result, unfolded
        after it)
    """

    V: np.ndarray
    F: np.ndarray
    M_E: np.ndarray
    edges: np.ndarray
    M_V: np.ndarray
    history: list[dict] = field(default_factory=list)
    iterations: int = 0
    stop_reason: str = ""
    noise_estimate: float = float("nan")
    params: dict = field(default_factory=dict)
    n_unfolded: int = 0

    @property
    def mesh(self):
        """The result as a ``trimesh.Trimesh`` (no processing, same vertex order)."""
        import trimesh

        return trimesh.Trimesh(self.V, self.F, process=False)


REORDER_MIN_VERTICES = 200_000
"""Meshes this large are solved in a Morton (Z-curve) order of vertices and faces: every kernel
is memory-bound there, and the reordering measured 1.33 s instead of 1.76 s per iteration on a
1.18M-vertex subdivided mesh. Smaller meshes keep their order (results then do not depend on a
coordinate-dependent ordering, which keeps the rotation test exact to rounding)."""


def locality_order(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertex and face permutations along a Morton (Z-order) curve.

    Returns
    -------
    pv : (nV,) int64, new vertex i is old vertex ``pv[i]``
    pf : (nF,) int64, order of the faces (in the renumbered mesh)
    """
    from ._kernels import morton

    pv = np.argsort(morton(V), kind="stable")
    inv = np.empty_like(pv)
    inv[pv] = np.arange(len(pv))
    pf = np.argsort(morton(V[pv][inv[F]].mean(axis=1)), kind="stable")
    return pv, pf


def _edge_values_to(topo, topo_w, pf: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Re-index per-edge ``values`` of the reordered mesh ``topo_w`` (its face m is face
    ``pf[m]`` of ``topo``, corners in the same order) onto ``topo.edges``, through the face-edge
    tables (edge k of a face joins its corners k and k + 1): two gathers instead of a search."""
    out = np.zeros(topo.n_edges, dtype=values.dtype)
    out[topo.face_edges[pf]] = values[topo_w.face_edges]
    return out


HEAVY_NOISE = 0.33
HEAVY_SLOPE = 600.0
"""Above this estimated level the robust stage grows by 600 iterations per unit of γ̂ (up to 120):
heavy noise is otherwise frozen in by the feature stage (measured in docs/parameters.md)."""


HEAVY_ROBUST_A = 0.25


def robust_a_from_noise(gamma: float) -> float:
    """Non-convexity of the robust stage: 0.5, or ``HEAVY_ROBUST_A`` above ``HEAVY_NOISE``."""
    return HEAVY_ROBUST_A if gamma > HEAVY_NOISE else 0.5


def robust_iters_from_noise(gamma: float, folded_fraction: float = 0.0) -> int:
    """Default length of the robust stage: ``clip(130 γ̂, 10, 40)``, or 40 when more than 1 % of
    the faces were folded over. ``denoise`` passes the larger of the MAD and RMS noise
    estimates, so impulsive noise (RMS 1.5× MAD) also gets the long stage.

    Measured (benchmarks in docs/parameters.md): at γ = 0.1 a 10-iteration robust stage halves
    MSAE against 40 on organic meshes (spot 59 → 41, rocker_arm 72 → 41) and on fandisk (8.4 →
    5.0); at γ = 0.3 the long stage is needed (fandisk 25 with 40, 49 with 10). Random-direction
    noise reads about half its level but still wants the long stage; its fold-overs give it away.
    """
    if gamma > HEAVY_NOISE:
        return int(np.clip(round(40 + HEAVY_SLOPE * (gamma - HEAVY_NOISE)), 40, 120))
    if folded_fraction > 0.01:
        return 40
    return int(np.clip(round(130.0 * gamma), 10, 40))


def lambda_from_noise(gamma: float) -> float:
    """Default fidelity weight λ for an estimated noise level γ̂ (mean edge lengths)."""
    return float(np.clip(0.02 / max(gamma, 1e-3) ** 2, 0.05, 1.0))


TANGENTIAL_MAX = 0.65
"""Below this :func:`meshrepair.scale.tangential_ratio` the noise is taken to lie along the
normals (measured 0.08-0.47 on normal noise, 0.83-1.29 on random-direction noise) and the
crease-supported region gets the tangential anchor of
:func:`meshrepair.fidelity.tangential_anchor`."""

UNFOLD_DATA_IMPULSIVE = True
"""Where the input had folded faces, the unfolded mesh (:func:`meshrepair.relax.untangle`) is
the *start* of the solve, and the fidelity term keeps the *input* as its data ``V⁰``, except for
impulsive noise, where the folds are made by thrown vertices and the unfolded positions are the
better data. Umbrella unfolding moves every vertex of a folded fan tangentially as well (nllr_igea:
2,601 of 8,268 vertices, 0.24 mean edge lengths rms), and a fidelity to it held that tangential
error in: measured in docs/parameters.md (gcn_trim_star_n3 MSAE 117.8 → 72.8, E_V ratio 1.27 →
0.86; fandisk γ0.7 183 → 151; held-out spot γ0.4 normal 324 → 509 is the one large loss)."""


def fidelity_data(V_input: np.ndarray, V_unfolded: np.ndarray, impulsive: bool) -> np.ndarray:
    """Data ``V⁰`` of the fidelity term: the input, or the unfolded mesh for impulsive noise
    (see :data:`UNFOLD_DATA_IMPULSIVE`)."""
    return V_unfolded if (impulsive and UNFOLD_DATA_IMPULSIVE) else V_input


UNFOLD_RESULT = True
"""Faces still folded over in the *result* are unfolded by the same umbrella step as the input,
cluster by cluster where the unfolded faces agree better with the robust probe's normals
(:func:`unfold_result`). With the input as data (:func:`fidelity_data`), a fold of the input on
a coarse mesh can survive both solves: at γ0.4 normal noise spot (2,930 vertices) kept 31 faces
folded (errors 57-170°), a third of its MSAE. Measured in docs/parameters.md (round 3): spot
γ0.4 normal 499 → 318, camelhead γ0.3 490 → 294, sharp_sphere 186 → 156, fandisk γ0.7 164 →
138, gcn_fandisk_n6 82 → 66; trim_star n3 73 → 77 (without the probe check 88: its true spikes,
whose faces meet at more than 90° in the truth too, were blunted)."""


def unfold_result(V_out: np.ndarray, topo, V_ref: np.ndarray | None = None
                  ) -> tuple[np.ndarray, int]:
    """The result with its locally folded faces unfolded.

    A face *f* is folded when ``⟨n_f, Σ_g n_g⟩ ≤ 0`` over its edge-neighbours *g*
    (:func:`meshrepair.relax.locally_flipped_faces`); the vertices of folded faces and their
    1-ring are moved to their neighbours' centroid until no face is folded
    (:func:`meshrepair.relax.untangle`, which keeps the iterate with the fewest folds, so a
    fold it cannot remove leaves the result unchanged). Vertices away from folds do not move.

    With a reference ``V_ref`` (``denoise`` passes the robust probe's result, which has no
    folds and keeps true spikes), each connected cluster K of moved vertices keeps its unfolded
    positions only when the faces touching it then agree better with the reference normals:

    .. math:: \\sum_{f \\sim K} \\angle(n_f(V_u), n_f(V_{ref}))
              < \\sum_{f \\sim K} \\angle(n_f(V_{out}), n_f(V_{ref})),

    so a true spike whose faces meet at more than 90° (trim_star's) is not blunted.

    Parameters
    ----------
    V_out : (nV, 3) float64, the solve's result
    topo : Topology of the mesh
    V_ref : (nV, 3) float64, optional reference for the per-cluster check

    Returns
    -------
    V : (nV, 3) float64, a new array (``V_out`` itself when nothing is folded)
    n_folded : int, faces folded in ``V_out``
    """
    from .relax import locally_flipped_faces

    n = int(locally_flipped_faces(V_out, topo).sum())
    if n == 0:
        return V_out, 0
    V, _ = untangle(V_out, topo)
    if V_ref is not None:
        V = _keep_consistent_clusters(V_out, V, V_ref, topo)
    return V, n


def _keep_consistent_clusters(V_out, V_unf, V_ref, topo):
    """Per connected cluster of moved vertices, keep the unfolded positions only where the
    faces touching the cluster agree better with the reference normals (see
    :func:`unfold_result`)."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    from .geometry import face_normals

    F = topo.faces
    moved = np.any(V_unf != V_out, axis=1)
    if not moved.any():
        return V_unf
    e = topo.edges[moved[topo.edges[:, 0]] & moved[topo.edges[:, 1]]]
    nV = topo.n_vertices
    A = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(nV, nV))
    _, lab = connected_components(A, directed=False)
    lab = np.where(moved, lab, -1)
    Nr = face_normals(V_ref, F)

    def ang(X):
        return np.arccos(np.clip(np.einsum("ij,ij->i", face_normals(X, F), Nr), -1.0, 1.0))

    a0, a1 = ang(V_out), ang(V_unf)
    fl = lab[F].max(axis=1)  # the moved vertices of a face are adjacent: one cluster
    m = fl >= 0
    nc = int(lab.max()) + 1
    d = np.bincount(fl[m], weights=a1[m] - a0[m], minlength=nc)
    keep = d < 0
    out = V_out.copy()
    sel = moved & keep[np.maximum(lab, 0)]
    out[sel] = V_unf[sel]
    return out


REANCHOR = True
REANCHOR_MAX_RATIO = 0.6
"""Tangential re-anchoring of the smooth region after the solve (:mod:`meshrepair.reproject`):
the result's vertices outside the crease-supported region slide along the result surface
towards the input's closest points, with the minimum-variance weights of
:func:`meshrepair.reproject.blend_weights`, when the residual tangential ratio
:func:`meshrepair.reproject.residual_tangential_ratio` reads noise along the normals
(``ρ_t < 0.6``) and the noise is not heavy (``γ̂ ≤ HEAVY_NOISE``). It runs before
:func:`unfold_result`, whose probe check then judges the final positions. Measured in
docs/parameters.md (issue 12, round 5): nllr_igea MSAE 230.7 → 222.4, E_V ratio 1.58 → 1.13;
nllr_nicolo E_V 1.22 → 1.07; every CAD row within ±0.2 %. Round 6: the targets are smoothed
tangentially (:func:`meshrepair.reproject.tangential_smooth`, the displacement from the input):
igea 222.4 → 218.8, E_V ratio 1.13 → 1.11, every hold-out row within +0.4 %."""


def _reanchor_smooth(V_in, V_out, F, topo, sup_v, gamma, info):
    """:data:`REANCHOR` on the vertices outside ``sup_v``; records its decision in ``info``."""
    from .reproject import reanchor, residual_tangential_ratio

    ratio = residual_tangential_ratio(V_out, V_in, F)
    info["reanchor_ratio"] = ratio
    if not (ratio < REANCHOR_MAX_RATIO) or gamma > HEAVY_NOISE:
        return V_out
    V_new, w = reanchor(V_out, V_in, F, ~sup_v, topo=topo)
    info["reanchored"] = int((w > 0).sum())
    el = float(np.linalg.norm(V_in[topo.edges[:, 0]] - V_in[topo.edges[:, 1]], axis=1).mean())
    shift = np.sqrt(np.mean(np.sum((V_new - V_out) ** 2, axis=1)))
    info["reanchor_shift"] = float(shift / el) if el > 0 else 0.0  # mean edge lengths
    log.info("re-anchored %d smooth-region vertices tangentially (residual ratio %.2f)",
             info["reanchored"], ratio)
    return V_new


PROBE_MAX_ITERS = 120
PROBE_EARLY_STOP = True
"""Cap of the robust probe that decides the crease-supported region."""

FLAT_SPREAD_DEFAULT = 7.0
"""Crease-supported edges whose robust-probe normal spread is below this (degrees) get the
flat-TV prior (MC with ``a = FLAT_A``) in the feature stage instead of edge-Willmore."""
FLAT_A = 0.5

IMPULSIVE_RATIO = 1.3
"""Noise whose RMS level exceeds its robust (MAD) level by this factor is called impulsive: a
minority of vertices moved far. Measured: Gaussian and Kinect inputs 1.00-1.10, the impulsive
inputs 1.48 (twelve, pierrot) and 2.3 (nicolo i2)."""


def is_impulsive(gamma: float, gamma_rms: float) -> bool:
    """``γ̂_rms > 1.3 γ̂_MAD`` (see :data:`IMPULSIVE_RATIO`)."""
    return bool(gamma_rms > IMPULSIVE_RATIO * max(gamma, 1e-12))


def huber_from_noise(gamma: float, gamma_rms: float) -> float:
    """Default threshold δ of the robust fidelity (:mod:`meshrepair.fidelity`): ``2 γ̂_rms``
    for impulsive noise, 0 (the paper's quadratic fidelity) otherwise."""
    return 2.0 * gamma_rms if is_impulsive(gamma, gamma_rms) else 0.0


def willmore_weight_from_scale(rho: float, impulsive: bool = False,
                               tangential: float = 0.0) -> float:
    """Weight ``w`` of edge-Willmore from the noise correlation ratio ρ of
    :func:`meshrepair.scale.noise_scale` (``ρ = 1`` for i.i.d. noise):

    .. math:: w = \\mathrm{clip}(1 + 150(ρ - 1.12),\\, 1,\\, 16),

    1 for white noise (ρ ≤ 1.12; the Gaussian inputs read 0.83-1.09), 16 for scanner-like noise
    correlated over ≥ 2 rings (ρ ≥ 1.22; the real Kinect scan reads 1.21-1.23).
    The quadratic prior ``w ||DN||²`` against the coupling ``β2 ||N - 𝒩(V)||²`` smooths the
    normals over about ``√(w/β2)`` rings, so a larger ``w`` acts at the scale of the noise.
    Impulsive noise raises ρ through its isolated spikes (w = 1), and so do noise with a
    tangential part and low noise on an irregular mesh (the tangential residual and the
    curvature left in the reference): the weight is raised only when the noise lies along the
    normals, ``tangential`` (:func:`meshrepair.scale.tangential_ratio`) < 0.65. Measured false
    positives without that test: rocker_arm γ0.1 normal (r_t 1.13, ρ 1.28), rocker_arm γ0.1
    random (r_t 2.22, ρ 1.35), spot / nicolo γ0.1 random (r_t 1.35 / 1.85, ρ 1.23 / 1.22); the
    real Kinect scan reads ρ 1.22 with r_t 0.34. Smooth synthetic correlated noise can read
    r_t ≥ 0.65 (its high-passed normal part is small) and is then missed (docs/parameters.md).
    """
    if impulsive or tangential >= TANGENTIAL_MAX:
        return 1.0
    return float(np.clip(1.0 + 150.0 * (rho - 1.12), 1.0, 16.0))


CAD_SUPPORT = 0.2
CAD_WILLMORE = 6.0
"""Rule of :func:`outside_weight`: a mesh whose crease-supported region covers at least
``CAD_SUPPORT`` of its edges is a CAD part, and edge-Willmore outside that region gets the
weight ``CAD_WILLMORE`` (times ``w``) in the feature stage."""


def outside_weight(support_fraction: float, tangential: float) -> float:
    """Factor on edge-Willmore *outside* the crease-supported region C, feature stage only:

    .. math:: w_{out} = \\begin{cases} 6 & |C| / n_E \\ge 0.2 \\text{ and } r_t < 0.65 \\\\
                                       1 & \\text{otherwise.} \\end{cases}

    Outside C a CAD part is smooth patches (planes, cylinders, blends) far from its creases.
    The quadratic prior ``w ||t_e||²`` against the coupling ``β2 ||N - 𝒩(V)||²`` averages the
    normals over about ``√(w/β2)`` rings; with ``w = 1`` it leaves a ripple of a few degrees
    there (tgv_fandisk: median face error 1.67° outside C against MeshTGV's 0.88°; inside C
    ours is already lower). ``w_out = 6`` averages over ≈ 1.5 rings more and measured 0.96°.
    It is quadratic, so it does not terrace the curved patches the flat-TV class would.

    The supported fraction separates the cases: CAD parts 0.41-0.64 (fandisk, twelve,
    sharp_sphere, trim_star, screwdriver), the organic meshes 0.04-0.10 (nicolo, igea,
    pierrot, bunny, rocker_arm: short left-over chains), so organic results do not change.
    Heavy noise on coarse organic meshes can read high (spot γ0.4 0.63, camelhead 0.96); there
    C covers nearly everything and the factor acts on little. Noise not along the normals
    (``r_t ≥ 0.65``, :data:`TANGENTIAL_MAX`) keeps 1: fandisk γ0.4 random lost 9 % with it.
    Measured in docs/parameters.md (round 4).
    """
    if support_fraction >= CAD_SUPPORT and tangential < TANGENTIAL_MAX:
        return CAD_WILLMORE
    return 1.0


POLISH = True
"""Heavy noise on a CAD part gets the crease-bounded polish of :mod:`meshrepair.polish`."""


def polish_rule(gamma: float, outside: float, willmore: float, length: float
                ) -> tuple[int, float, int] | None:
    """Whether the result is polished (:mod:`meshrepair.polish`) and with which ring count
    ``r``, flatness threshold ``τ`` (degrees) and number of passes:

    .. math:: \\text{polish} \\iff (\\max(γ̂, γ̂_{rms}) > 0.33 \\wedge w_{out} > 1)
              \\vee w > 1, \\qquad
              r = \\mathrm{round}(4 \\max(1, ℓ)),\\; τ = 5° \\max(1, ℓ),\\;
              n_{pass} = \\mathrm{round}(10 \\max(1, ℓ^2)),

    heavy noise (:data:`HEAVY_NOISE`) on a CAD part with the noise along the normals (the
    rule of :func:`outside_weight`), or noise found correlated along the normals (``w > 1``,
    :func:`willmore_weight_from_scale`), with ``ℓ`` its correlation length (0 for white
    noise). A bump ``ℓ`` edges wide is averaged by a neighbourhood ``ℓ`` times wider; its
    residual slopes are larger (hence τ), and the filter-and-move passes diffuse, like the
    V-steps of :func:`inner_iters_from_scale`, over about ``ℓ²`` times as many passes.
    At moderate white noise the feature stage already leaves the flat patches within 2°
    (tgv_fandisk) and the same filter on gcn_trim_star_n3 (γ̂ 0.27) without the gate measured
    75 → 129; organic meshes and random-direction noise have no converged crease mask to
    bound it. Measured in docs/parameters.md (round 5): gcn_fandisk_n6 MSAE 58.7 → 51.5,
    fandisk γ0.7 124.3 → 113.4; the Kinect scan 167.6 → 155.0 (ℓ = √2: r = 6, τ = 7.1°, 20
    passes).
    """
    heavy = gamma > HEAVY_NOISE and outside > 1.0
    if not POLISH or not (heavy or willmore > 1.0):
        return None
    ell = max(1.0, float(length)) if willmore > 1.0 and np.isfinite(length) else 1.0
    return int(round(4 * ell)), 5.0 * ell, int(round(10 * ell * ell))


def inner_iters_from_scale(length: float, base: int = 3) -> int:
    r"""V-steps per ADMM iteration for noise correlated over ``ℓ`` mean edge lengths
    (:func:`meshrepair.scale.noise_scale`), used when the noise is found correlated (``w > 1``):

    .. math:: n_{inner} = \mathrm{clip}(\mathrm{round}(3\, \max(1, ℓ^2)),\, 3,\, 12).

    The V-update (26) is solved by a few preconditioned gradient steps, each moving a vertex
    from its 1-ring: a bump of the vertices ``ℓ`` rings wide needs about ``ℓ²`` times as many
    local steps to follow the smoothed normals as a one-ring bump (diffusion). On the real
    Kinect scan (``ℓ ≈ 1.4-1.7``) the ADMM normals and the mesh's own normals keep the same
    error (184 / 184 deg²), so the vertices, not the prior, hold the low-frequency bumps in;
    3 / 6 / 10 / 20 steps (probe and solve): MSAE 184 / 167 / 169 / 170. The probe is run
    again with the new count (the correlation is known only after a first probe): its better
    converged normals keep a few crease chains (support 0 → 2.6 % of the edges); with 6 steps
    in the final solve only, 176. On i.i.d. heavy noise more steps hurt (gcn_fandisk_n6 64 →
    78 with 6), hence only for correlated noise (``w > 1``).
    """
    return int(np.clip(round(base * max(1.0, float(length) ** 2)), base, 12))


def default_stages(*, robust_iters: int = 40, feature_iters: int = 60, a: float = 10.0,
                   flat_a: float = 0.0, robust_a: float = 0.5) -> tuple[Stage, ...]:
    """The two-stage schedule described in the module docstring."""
    return (
        Stage(a=robust_a, eps=2.0, beta2_ratio=10.0, mask="all", max_iter=robust_iters,
              switch_tol=2e-4, min_iter=min(10, robust_iters), willmore_edges=False,
              name="robust"),
        Stage(a=a, eps=1.2, beta2_ratio=20.0 / 12.0, mask="adaptive", max_iter=feature_iters,
              flat_a=flat_a, name="feature"),
    )


def denoise(
    V,
    F=None,
    *,
    lam: float | None = None,
    th: float = 30.0,
    a: float = 10.0,
    robust_iters: int | None = None,
    feature_iters: int = 60,
    mask_update_every: int = 3,
    min_feature_edges: int = 6,
    tol: float = 1e-6,
    unfold: bool = True,
    inner_solver: str = "armijo",
    inner_iters: int | None = None,
    n_solver: str = "auto",
    stages: tuple[Stage, ...] | None = None,
    huber_delta: float | None = None,
    willmore_weight: float | None = None,
    regions: bool = True,
    polish: bool = True,
    callback: Callable[[dict], None] | None = None,
) -> DenoiseResult:
    """Denoise a triangle mesh, keeping sharp features (energy (6) minimised by ADMM).

    Parameters
    ----------
    V : (nV, 3) float array, or a ``trimesh.Trimesh`` (then ``F`` is omitted)
    F : (nF, 3) int array
    lam : fidelity weight λ per squared mean edge length; default from the estimated noise.
    th : dihedral threshold (degrees) of the sharp-edge mask (5).
    a : MC non-convexity of the feature stage.
    robust_iters : cap of the robust stage; default from the noise: ``clip(130 γ̂, 10, 40)`` with
        γ̂ the larger of the MAD and RMS estimates, and
        40 when more than 1 % of the faces were folded over (noise with a tangential part).
    feature_iters : cap of the feature stage.
    mask_update_every : refresh M_E every this many feature-stage iterations (0: never).
    min_feature_edges : keep only sharp edges in chains of at least this many edges (1: all).
    tol : rule (35) tolerance.
    unfold : unfold folded-over faces before the solve, and those still folded after it.
    inner_solver : V-subproblem solver (``"armijo"``, ``"gd"``, ``"heavy_ball"``, ``"lbfgs"``,
        ``"bfgs"``).
    inner_iters : inner iterations per ADMM iteration; default 3, more for correlated noise
        (:func:`inner_iters_from_scale`).
    n_solver : N-subproblem solver (``"auto"``, ``"cg"``, ``"direct"``).
    stages : a custom schedule replacing the default two stages (then no region probe).
    huber_delta : threshold δ of the robust Huber fidelity (:mod:`meshrepair.fidelity`), mean
        edge lengths; default from the noise (``2 γ̂_rms`` when the noise looks impulsive,
        ``γ̂_rms > 1.3 γ̂``, else 0 = quadratic); 0 turns it off.
    willmore_weight : weight of edge-Willmore on smooth edges; default from the correlation of
        the noise (:func:`willmore_weight_from_scale`).
    regions : decide per region whether a crease is supported (:mod:`meshrepair.regions`) from a
        first robust probe, and use the smooth prior only elsewhere; ``False`` runs the MC stages
        on the whole mesh without probe, flat-TV class, anchor, correlated-noise weight or
        tangential re-anchoring (the heavy-noise and impulsive rules still apply).
    polish : apply the automatic polish rule (:func:`polish_rule`, :mod:`meshrepair.polish`);
        ``False`` never polishes.
    callback : called with each iteration's history entry; raise
        :class:`meshrepair.solver.StopRequested` to stop early.

    Returns
    -------
    DenoiseResult
        The input arrays are never modified.

    Raises
    ------
    MeshRepairError
        For invalid meshes (see :func:`meshrepair.validate.check_mesh`) or options.
    """
    from .io import as_arrays

    V, F = as_arrays(V, F)
    with heap_allocations():
        return _denoise(V, F, lam=lam, th=th, a=a, robust_iters=robust_iters,
                        feature_iters=feature_iters, mask_update_every=mask_update_every,
                        min_feature_edges=min_feature_edges, tol=tol, unfold=unfold,
                        inner_solver=inner_solver, inner_iters=inner_iters,
                        n_solver=n_solver, stages=stages, huber_delta=huber_delta,
                        willmore_weight=willmore_weight, regions=regions, polish=polish,
                        callback=callback)


COLLAPSE_VOLUME_RATIO = 0.5
"""A closed mesh whose enclosed volume falls below this fraction of the input's is collapsed:
measured with the defaults on the 7 closed shared meshes (fandisk, spot, trim_star, twelve,
rocker_arm, sharp_sphere, screwdriver) at γ = 0.3, normal and random directions, the ratio stays
in [0.9967, 1.0071], while the robust stage flattens a tetrahedron with γ = 0.1 to 1 % of its
volume."""


def _volume_ratio(V: np.ndarray, V_out: np.ndarray, F: np.ndarray, report) -> float | None:
    """Signed volume of the result over the input's, for a closed mesh with a clear volume
    (``|vol| > 1e-6 diag³``); None otherwise."""
    if not report.is_closed or len(F) == 0:
        return None

    from ._kernels.faces import signed_volume

    c = V.mean(axis=0)
    v_in = signed_volume(V, F, c)
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    if not np.isfinite(v_in) or abs(v_in) <= 1e-6 * diag**3:
        return None
    return signed_volume(V_out, F, c) / v_in


def _denoise(V, F, *, lam, th, a, robust_iters, feature_iters, mask_update_every,
             min_feature_edges, tol, unfold, inner_solver, inner_iters, n_solver, stages,
             huber_delta, willmore_weight, regions, callback, polish=True) -> DenoiseResult:
    from .options import check_bool, check_int, check_number
    from .validate import _check_mesh

    # every option first (finite, in range), before any work on the mesh
    lam = check_number("lam", lam, low=0, allow_none=True)
    a = check_number("a", a, low=0, low_open=True)
    robust_iters = check_int("robust_iters", robust_iters, low=0, allow_none=True)
    feature_iters = check_int("feature_iters", feature_iters, low=0)
    mask_update_every = check_int("mask_update_every", mask_update_every, low=0)
    min_feature_edges = check_int("min_feature_edges", min_feature_edges, low=1)
    auto_inner = inner_iters is None
    inner_iters = check_int("inner_iters", 3 if auto_inner else inner_iters, low=1)
    tol = check_number("tol", tol, low=0, low_open=True)
    unfold = check_bool("unfold", unfold)
    regions = check_bool("regions", regions)
    polish = check_bool("polish", polish)
    huber_delta = check_number("huber_delta", huber_delta, low=0, low_open=True, allow_none=True)
    willmore_weight = check_number("willmore_weight", willmore_weight, low=0, low_open=True,
                                   allow_none=True)
    if callback is not None and not callable(callback):
        raise MeshRepairError(f"callback must be callable or None, got {type(callback).__name__}")
    if stages is not None:
        stages = tuple(stages)
    SolverOptions(th=th, tol=tol, inner_solver=inner_solver, inner_iters=inner_iters,
                  n_solver=n_solver, mask_update_every=mask_update_every,
                  min_feature_edges=min_feature_edges,
                  **({"stages": stages} if stages else {})).validate()
    report, topo = _check_mesh(V, F, name="input mesh")
    gamma, gamma_rms = noise_statistics(V, F, topo)
    impulsive = is_impulsive(gamma, gamma_rms)
    lam_used = lambda_from_noise(gamma) if lam is None else float(lam)
    delta = huber_from_noise(gamma, gamma_rms) if huber_delta is None else float(huber_delta)
    opts_kw = dict(lam=lam_used, huber_delta=delta, th=th, tol=tol, inner_solver=inner_solver,
                   inner_iters=inner_iters, n_solver=n_solver,
                   mask_update_every=mask_update_every, min_feature_edges=int(min_feature_edges))
    SolverOptions(**opts_kw).validate()  # fail fast on bad options
    log.info("denoise: %d vertices, %d faces, noise estimate %.3f (rms %.3f), lambda %.3g",
             len(V), len(F), gamma, gamma_rms, lam_used)
    Vs = V
    n_unf = 0
    if unfold:
        from .relax import locally_flipped_faces

        n_unf = int(locally_flipped_faces(V, topo).sum())
        if n_unf:
            Vs, left = untangle(V, topo)
            log.info("unfolded %d folded-over faces (%d left)", n_unf - left, left)
    auto_robust = robust_iters is None and stages is None
    if robust_iters is None:
        robust_iters = robust_iters_from_noise(max(gamma, gamma_rms), n_unf / max(len(F), 1))
    probe = stages is None and regions
    if stages is None:
        stages = default_stages(robust_iters=int(robust_iters), feature_iters=int(feature_iters),
                                a=a, flat_a=FLAT_A if regions else 0.0,
                                robust_a=robust_a_from_noise(max(gamma, gamma_rms)))
    reorder = len(V) >= REORDER_MIN_VERTICES
    if reorder:  # run on a cache-friendly copy, map the result back exactly
        pv, pf = locality_order(Vs, F)
        inv = np.empty_like(pv)
        inv[pv] = np.arange(len(pv))
        Fw, Vw, Vd = inv[F][pf], Vs[pv], V[pv]
        from .topology import edge_topology

        topo_w = edge_topology(Fw, len(V))
    else:
        Fw, Vw, Vd, topo_w = F, Vs, V, topo
    Vd = fidelity_data(Vd, Vw, impulsive)
    Vi = None if Vd is Vw else Vw
    info = {"tangential_ratio": float("nan"), "support_fraction": float("nan"),
            "outside_weight": 1.0,
            "willmore_weight": 1.0, "noise_rho": float("nan"), "noise_length": float("nan"),
            "noise_gamma_scale": float("nan")}
    force = flat = anchor = wedges = None
    r1_V = None
    sup_v = None  # vertices of the crease-supported region, input order
    ww = 1.0 if willmore_weight is None else float(willmore_weight)
    if probe and stages[0].max_iter > 0:
        n1 = int(min(stages[0].max_iter, PROBE_MAX_ITERS))
        st1 = replace(stages[0], max_iter=n1, min_iter=min(stages[0].min_iter, n1))
        # the probe is a one-stage run: its stage's switch rule becomes the stopping rule
        kw1 = {**opts_kw, "tol": st1.switch_tol if PROBE_EARLY_STOP else opts_kw["tol"]}
        Vn_w = V[pv] if reorder else V
        r1 = ADMMSolver(Fw, len(V), options=SolverOptions(stages=(st1,), **kw1),
                        topo=topo_w).solve(Vd, Vi)
        tr = tangential_ratio(Vn_w, Fw, r1.V, topo=topo_w)
        ns = noise_scale(Vn_w, Fw, reference=r1.V, topo=topo_w)
        if willmore_weight is None:
            ww = willmore_weight_from_scale(ns.rho, impulsive, tr)
        if auto_inner and ww > 1.0:  # correlated noise: more V-steps for its long waves,
            inner_iters = inner_iters_from_scale(ns.length)  # in the probe too (its creases)
            opts_kw["inner_iters"] = inner_iters
            if inner_iters != kw1["inner_iters"]:
                kw1["inner_iters"] = inner_iters
                r1 = ADMMSolver(Fw, len(V), options=SolverOptions(stages=(st1,), **kw1),
                                topo=topo_w).solve(Vd, Vi)
                tr = tangential_ratio(Vn_w, Fw, r1.V, topo=topo_w)
        r1_V = r1.V[inv] if reorder else r1.V
        sup = crease_support(topo_w, r1.N, th=th)
        force = np.where(sup, -1, 0).astype(np.int8)
        sup_v = np.zeros(len(V), bool)
        sup_v[topo_w.edges[sup].ravel()] = True
        if reorder:
            sup_v = sup_v[inv]
        flat = flat_edges(topo_w, r1.N, sup, max_spread=FLAT_SPREAD_DEFAULT)
        if tr < TANGENTIAL_MAX and sup.any():  # noise along the normals: anchor the CAD region
            anchor = np.zeros(len(V))
            anchor[topo_w.edges[sup].ravel()] = 1.0
        info["tangential_ratio"] = tr
        if lam is None and ww > 1.0:  # correlated noise: λ from its level at its own scale
            lam_used = lambda_from_noise(max(gamma, ns.gamma))
            opts_kw["lam"] = lam_used
        w_out = outside_weight(float(sup.mean()), tr) if willmore_weight is None else 1.0
        if w_out != 1.0:  # a CAD part: its smooth patches get the stronger smooth prior
            wedges = np.where(sup, ww, ww * w_out)
        info["outside_weight"] = w_out
        info.update(support_fraction=float(sup.mean()), willmore_weight=ww,
                    noise_rho=ns.rho, noise_length=ns.length, noise_gamma_scale=ns.gamma)
        log.info("crease support on %.1f %% of the edges; noise correlation %.2f (length %.1f, "
                 "level %.3f); willmore weight %g", 100 * sup.mean(), ns.rho, ns.length,
                 ns.gamma, ww)

    def solve(stages_):
        """The main run; on a reordered copy the result is mapped back exactly."""
        opts = SolverOptions(stages=tuple(stages_), willmore_weight=ww, **opts_kw)
        res = ADMMSolver(Fw, len(V), options=opts, topo=topo_w, edge_force=force,
                         flat_edges=flat, anchor=anchor, willmore_edges=wedges
                         ).solve(Vd, Vi, callback=callback)
        if reorder:
            return res, res.V[inv], _edge_values_to(topo, topo_w, pf, res.M_E)
        return res, res.V, res.M_E

    res, V_out, M_E = solve(stages)
    shrink = _volume_ratio(V, V_out, F, report)
    if shrink is not None and shrink < COLLAPSE_VOLUME_RATIO and res.stop_reason != "interrupted":
        if not auto_robust:
            raise MeshRepairError(
                f"denoise collapsed this closed mesh: its volume fell to {shrink:.3g} of the "
                f"input's ({len(V)} vertices; a mesh this coarse has no smooth regions for the "
                "model). Try robust_iters=0 (no robust stage) or a finer mesh")
        log.warning("denoise: the robust stage collapsed this coarse closed mesh (volume ratio "
                    "%.3g, %d vertices); solving again without it", shrink, len(V))
        robust_iters = 0
        # the probe's decisions came from the collapsed robust run: drop them too
        force = flat = anchor = wedges = sup_v = None
        ww = 1.0 if willmore_weight is None else float(willmore_weight)
        lam_used = lambda_from_noise(gamma) if lam is None else float(lam)
        opts_kw["lam"] = lam_used
        stages = default_stages(robust_iters=0, feature_iters=int(feature_iters), a=a,
                                flat_a=FLAT_A if regions else 0.0,
                                robust_a=robust_a_from_noise(max(gamma, gamma_rms)))
        res, V_out, M_E = solve(stages)
        shrink = _volume_ratio(V, V_out, F, report)
        if shrink is not None and shrink < COLLAPSE_VOLUME_RATIO:
            raise MeshRepairError(
                f"denoise collapsed this closed mesh: its volume fell to {shrink:.3g} of the "
                f"input's even without the robust stage ({len(V)} vertices; a mesh this coarse "
                "has no smooth regions for the model); it cannot be denoised")
    info["polished"] = 0.0
    # the rule reads the automatic decisions only (a user-set Willmore weight is not a finding)
    pr = polish_rule(max(gamma, gamma_rms), info["outside_weight"],
                     ww if willmore_weight is None else 1.0, info["noise_length"])
    if polish and pr is not None:
        from .polish import polish as _polish

        V_out, info["polished"] = _polish(V_out, F, M_E, topo, rings=pr[0], tau=pr[1],
                                          passes=pr[2])
        log.info("polish (%d rings, %.1f deg, %d passes) on %.1f %% of the faces", *pr,
                 100 * info["polished"])
    info.update(reanchor_ratio=float("nan"), reanchored=0, reanchor_shift=0.0)
    if REANCHOR and sup_v is not None:  # before the unfolding: it judges the final positions
        V_out = _reanchor_smooth(V, V_out, F, topo, sup_v, max(gamma, gamma_rms), info)
    n_res_folded = 0
    if unfold and UNFOLD_RESULT:
        V_out, n_res_folded = unfold_result(V_out, topo, r1_V)
        if n_res_folded:
            log.info("unfolded %d faces folded over in the result", n_res_folded)
    return DenoiseResult(
        V=V_out,
        F=F,
        M_E=M_E,
        edges=topo.edges.copy(),
        M_V=res.M_V,
        history=res.history,
        iterations=res.iterations,
        stop_reason=res.stop_reason,
        noise_estimate=gamma,
        params={"lam": lam_used, "th": th, "a": a, "robust_iters": robust_iters,
                "feature_iters": feature_iters, "mask_update_every": mask_update_every,
                "min_feature_edges": min_feature_edges,
                "tol": tol, "inner_solver": inner_solver, "inner_iters": inner_iters,
                "n_solver": n_solver, "unfold": unfold, "n_components": report.n_components,
                "reordered": reorder, "huber_delta": delta, "impulsive": impulsive,
                "regions": probe,
                "fidelity_data": "input" if (Vd is not Vw or not n_unf) else "unfolded",
                "result_folds_unfolded": n_res_folded, **info},
        n_unfolded=n_unf,
    )
