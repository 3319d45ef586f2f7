"""CAD finish: the one-ring guidance filter on the flat sides of a CAD part's creases.

After the feature stage (and the heavy-noise polish of :mod:`meshrepair.denoise.polish`) the faces
of a CAD part keep a one-ring ripple of their normals, on the planar patches and on the flat
sides of the converged creases ``M_E``. The organic finish (:mod:`meshrepair.denoise.organic`)
removes that ripple on meshes without crease support; this module applies the same filter on
CAD parts, where it must keep the creases.

**Neighbourhood (one-sided).** ``K(f)`` is ``f`` and the faces sharing an edge with ``f`` that is
not in ``M_E`` (:func:`meshrepair.denoise.polish._neighbourhood_csr` with ``r = 1``). A face
adjacent
to a crease therefore averages only normals from its own side of the crease: the filter is
one-sided by construction, and no normal crosses ``M_E``.

**How strongly (the gate).** With ``V_E`` the vertices of the edges of ``M_E`` and the
one-sided spread of the result's normals over ``K(f)``

.. math:: s_f = \\Big(\\frac{1}{|K(f)|} \\sum_{g \\in K(f)} \\angle(n_g, m_f)^2\\Big)^{1/2},
          \\qquad m_f = \\frac{\\sum_{g \\in K(f)} n_g}{\\|\\cdot\\|},

.. math:: G = \\{f : f \\cap V_E = \\emptyset\\} \\;\\cup\\;
              \\{f : f \\cap V_E \\neq \\emptyset,\\; s_f < τ\\}, \\qquad τ = 5°,

computed once on the input of the finish (τ is the flatness threshold of the polish,
:data:`meshrepair.denoise.polish.POLISH_TAU`). Faces away from the creases and faces on a flat side
of a
crease (on a CAD part's flat sides ``s_f`` reads 0.2-0.8°, median) get the range width
``σ_s = 0.2``; a face touching the crease whose own side is curved or rippled within one ring
(``s_f ≥ τ``: the curved sides of a spike or a blend, several degrees) gets the narrow
``σ_s' = 0.1``, so it averages only with neighbours whose normals are within a few degrees of
its own and the crease is not rounded (docs/parameters.md: the wide σ_s on every face rounds
sharp spikes, and leaving those faces out entirely gives up a large part of the gain).

**Filter and vertex update** (the guidance of :mod:`meshrepair.denoise.organic`): per pass,

.. math:: n'_f = \\frac{\\sum_{g \\in K(f)} A_g\\, e^{-\\|c_f - c_g\\|^2 / 2σ_c^2}\\,
                       e^{-\\|n_f - n_g\\|^2 / 2σ_f^2}\\, n_g}{\\|\\cdot\\|},
          \\qquad σ_c = \\bar\\ell,\\; σ_f = σ_s \\text{ on } G,\\; σ_s' \\text{ off } G,

then 10 Sun et al. (2007) steps
``x_i ← x_i + (1/|F_i|) Σ_{f ∋ i} n'_f ⟨n'_f, c_f − x_i⟩`` (gradient steps on
``E(x) = Σ_f Σ_{i ∈ f} ⟨n'_f, x_i − c_f⟩²``); ``p`` passes (:func:`cad_finish_rule`).

**Properties.** A piecewise-planar mesh whose creases are all in ``M_E`` is a fixed point (every
``K(f)`` lies in one plane: the filter returns ``n_f`` and ``c_f − x_i`` lies in the face's
plane). The map commutes with rotations and translations, and with uniform scalings (``σ_c``
is the mean edge length of its input, the range kernel and the gate read angles only).
"""

from __future__ import annotations

import numpy as np

from meshrepair.denoise.polish import (
    POLISH_TAU,
    _neighbourhood_csr,
    _normals_areas,
    filter_normals,
    flat_gate_csr,
    vertex_update,
)

CAD_FINISH = True
"""The automatic CAD finish of :func:`cad_finish_rule` (False: never)."""

CAD_SIGMA_S = 0.2
CAD_SIGMA_S_CURVED = 0.1
CAD_VSTEPS = 10
CAD_TAU = POLISH_TAU
CAD_GAMMA_UNIT = 0.09
"""Noise level (mean edge lengths) per pass, as in
:func:`meshrepair.denoise.rules.guidance_rule`."""


def cad_finish_rule(gamma: float, outside: float, willmore: float) -> int:
    """Passes ``p`` of the CAD finish, 0 for none:

    .. math:: p = \\begin{cases} \\mathrm{clip}(\\mathrm{round}(γ̂ / 0.09), 1, 3) &
              w_{out} > 1 \\wedge w = 1 \\\\ 0 & \\text{otherwise,} \\end{cases}

    on CAD parts (the outside-weight rule of :func:`meshrepair.denoise.rules.outside_weight`
    fired: the crease-supported region covers ≥ 20 % of the edges and the noise lies along the
    normals) with white noise (the Willmore weight of
    :func:`meshrepair.denoise.rules.willmore_weight_from_scale` is 1: correlated scanner noise
    has its own polish at the noise's scale); heavy noise included (the finish runs after the
    polish). The number of passes is the organic guidance's own rule (one per 0.09 mean edge
    lengths of γ̂, the MAD estimate): the one-ring ripple left grows with the noise
    (docs/parameters.md).
    """
    if not CAD_FINISH or not outside > 1.0 or willmore != 1.0 or not np.isfinite(gamma):
        return 0
    return int(np.clip(round(gamma / CAD_GAMMA_UNIT), 1, 3))


def crease_side_gate(V: np.ndarray, F: np.ndarray, sharp: np.ndarray, topo, *,
                     tau: float = CAD_TAU, K=None, N: np.ndarray | None = None) -> np.ndarray:
    """The gate ``G`` of the module docstring (``(nF,)`` bool).

    Parameters
    ----------
    V : (nV, 3) float64
    F : (nF, 3) int64
    sharp : (nE,) bool, ``M_E`` on ``topo.edges``
    topo : Topology of the mesh
    tau : flatness threshold τ (degrees) for the faces touching a vertex of ``M_E``
    K : the neighbourhood ``K`` (CSR) if already built
    N : (nF, 3) the unit face normals of ``V`` (``polish._normals_areas``) if already computed
    """
    F = np.asarray(F, dtype=np.int64)
    sharp = np.asarray(sharp, bool)
    on_crease = np.zeros(len(V), bool)
    on_crease[topo.edges[sharp].ravel()] = True
    touch = on_crease[F].any(axis=1)
    if not touch.any():
        return np.ones(len(F), bool)
    if K is None:
        K = _neighbourhood_csr(topo, sharp, 1)
    if N is None:
        N, _, _ = _normals_areas(np.asarray(V, dtype=np.float64), F)
    return ~touch | flat_gate_csr(N, K, tau)


def finish_targets(X: np.ndarray, F: np.ndarray, K, gate: np.ndarray, *, sigma_c: float,
                   sigma_s: float = CAD_SIGMA_S, sigma_s_curved: float = CAD_SIGMA_S_CURVED,
                   faces: tuple | None = None) -> np.ndarray:
    """The target normals ``n'`` of one pass (module docstring): the bilateral filter over the
    CSR neighbourhood ``K`` with range width ``σ_s`` on ``gate`` and ``σ_s'`` off it (faces
    off the gate keep their normals when ``σ_s' = 0``); ``(nF, 3)``, unit rows. ``faces``:
    ``_normals_areas(X, F)`` if already computed (both filters read the same)."""
    faces = _normals_areas(X, F) if faces is None else faces
    Nt = filter_normals(X, F, K, gate, sigma_c=sigma_c, sigma_s=sigma_s, faces=faces)
    off = ~np.asarray(gate, bool)
    if sigma_s_curved > 0 and off.any():
        Nc = filter_normals(X, F, K, off, sigma_c=sigma_c, sigma_s=sigma_s_curved,
                            faces=faces)
        Nt[off] = Nc[off]
    return Nt


def cad_finish(V: np.ndarray, F: np.ndarray, sharp: np.ndarray, topo, *, passes: int,
               tau: float = CAD_TAU, sigma_s: float = CAD_SIGMA_S,
               sigma_s_curved: float = CAD_SIGMA_S_CURVED, steps: int = CAD_VSTEPS
               ) -> tuple[np.ndarray, float]:
    """The CAD finish of the module docstring.

    Parameters
    ----------
    V : (nV, 3) float64, the solve's result
    F : (nF, 3) int64
    sharp : (nE,) bool, ``M_E`` on ``topo.edges`` (bounds the neighbourhoods)
    topo : Topology of the mesh
    passes : filter-and-move passes ``p`` (0 returns a copy)
    tau : the gate's flatness threshold τ (degrees)
    sigma_s : range width σ_s of the normal kernel on ``G``
    sigma_s_curved : range width σ_s' off ``G`` (0: those faces keep their normals)
    steps : Sun et al. vertex steps per pass

    Returns
    -------
    V : (nV, 3) float64, a new array
    gated : float, the fraction of faces in ``G``
    """
    F = np.asarray(F, dtype=np.int64)
    X = np.array(V, dtype=np.float64, copy=True)
    if passes <= 0 or len(F) == 0:
        return X, 0.0
    sharp = np.asarray(sharp, bool)
    K = _neighbourhood_csr(topo, sharp, 1)
    faces = _normals_areas(X, F)  # of the first pass's X: the gate reads the same normals
    gate = crease_side_gate(X, F, sharp, topo, tau=tau, K=K, N=faces[0])
    le = float(np.linalg.norm(X[topo.edges[:, 0]] - X[topo.edges[:, 1]], axis=1).mean())
    for p in range(int(passes)):
        Nt = finish_targets(X, F, K, gate, sigma_c=le, sigma_s=sigma_s,
                            sigma_s_curved=sigma_s_curved, faces=faces if p == 0 else None)
        X = vertex_update(X, F, Nt, steps)
    return X, float(gate.mean())
