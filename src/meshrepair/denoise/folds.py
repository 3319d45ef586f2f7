"""Checks and repairs of a denoising result: the fidelity data where the input was folded,
faces still folded in the result (unfolded cluster by cluster where the robust probe agrees),
and the volume test that catches a collapsed closed mesh (docs/parameters.md).

Used by :func:`meshrepair.denoise` (which re-exports these names).
"""

from __future__ import annotations

import logging

import numpy as np

from meshrepair.model.relax import locally_flipped_faces, untangle

log = logging.getLogger("meshrepair.denoise.run")

UNFOLD_DATA_IMPULSIVE = True
"""Where the input had folded faces, the unfolded mesh (:func:`meshrepair.model.relax.untangle`) is
the *start* of the solve, and the fidelity term keeps the *input* as its data ``V⁰``, except for
impulsive noise, where the folds are made by thrown vertices and the unfolded positions are the
better data. Umbrella unfolding moves every vertex of a folded fan tangentially as well (up to
a third of the vertices, about 0.25 mean edge lengths rms), and a fidelity to it would hold that
tangential error in; with thrown vertices the unfolded positions are nearer the truth than the
input (docs/parameters.md)."""


def unfolded_input(V: np.ndarray, topo) -> tuple[np.ndarray, int]:
    """``(Vs, n)``: the input with its ``n`` folded-over faces untangled (``V`` when none)."""
    flipped = locally_flipped_faces(V, topo)
    n_unf = int(flipped.sum())
    if not n_unf:
        return V, 0
    Vs, left = untangle(V, topo, flipped=flipped)
    log.info("unfolded %d folded-over faces (%d left)", n_unf - left, left)
    return Vs, n_unf


def fidelity_data(V_input: np.ndarray, V_unfolded: np.ndarray, impulsive: bool) -> np.ndarray:
    """Data ``V⁰`` of the fidelity term: the input, or the unfolded mesh for impulsive noise
    (see :data:`UNFOLD_DATA_IMPULSIVE`)."""
    return V_unfolded if (impulsive and UNFOLD_DATA_IMPULSIVE) else V_input


UNFOLD_DATA_TANGENTIAL_MAX = 0.65
"""Tangential ratio (:func:`meshrepair.denoise.scale.tangential_ratio`, the probe's r_t) from which
the
folds of an impulsive-reading input are put down to a tangential part of the noise, not to
thrown vertices (:func:`unfolded_data_after_probe`); the value is
:data:`meshrepair.denoise.rules.TANGENTIAL_MAX`, the one threshold that tells noise along the
normals (r_t 0.08-0.47) from noise with a tangential part (0.83-1.29)."""

UNFOLD_DATA_CAD_SUPPORT = 0.2
"""The direction reading is trusted on CAD parts only, crease support ≥ 0.2 of the edges
(:data:`meshrepair.denoise.rules.CAD_SUPPORT`)."""


def unfolded_data_after_probe(impulsive: bool, tangential: float,
                              support_fraction: float = 1.0) -> bool:
    """Whether the main run keeps the unfolded mesh as its fidelity data, once the probe has
    read the direction of the noise (the probe itself runs on :func:`fidelity_data`):

    .. math:: V^0_{main} = \\begin{cases} V_{input} & \\text{impulsive} \\wedge
                  |C| / n_E \\ge 0.2 \\wedge r_t \\ge 0.65 \\\\
                  V^0 \\text{ of } \\texttt{fidelity\\_data} & \\text{otherwise,}
                  \\end{cases}

    ``r_t`` the probe's :func:`meshrepair.denoise.scale.tangential_ratio`, ``|C| / n_E`` the share
    of
    the edges in the crease-supported region (:func:`meshrepair.denoise.regions.crease_support`).
    Returns True when the main run keeps the unfolded mesh (``impulsive`` and not the first
    case).

    Why. The solve's normals follow the data where the prior lets them: the prior of (6)
    removes the part of the data error ``e = ⟨V⁰ - V*, n⟩`` that varies from vertex to vertex
    and keeps its smooth part, about ``W² e`` (``W`` the one-ring mean). The unfolding
    (:func:`meshrepair.model.relax.untangle`) replaces the input's error at a folded fan by an
    umbrella average, whose error is smooth over the fan: the curvature and crease rounding
    of the umbrella step. Whether that pays depends on what folded the fan:

    * vertices thrown along the normals (impulsive noise, ``r_t < 0.65``): the raw error at the
      moved vertices is large and the unfolding removes about half of it, at a like smooth
      error ``W² e``;
    * a tangential part of the noise (``r_t ≥ 0.65``: in-plane moves fold faces without any
      outlier): the raw error is hardly reduced while its smooth part grows (about 1.6-2×).

    The direction is read on CAD parts only (``|C| / n_E ≥ 0.2``, the test of
    :func:`meshrepair.denoise.rules.outside_weight`): on organic meshes ``r_t`` also reads
    curvature left in the probe (above 1 for white normal noise) and thrown vertices along the
    normals read 0.75-1.53 there, whose folds are the first case above. The reading is not
    perfect on CAD parts either: thrown vertices near thin parts can read 0.70-0.80 and then
    take the input as data, where the two choices measure about the same.

    Random-direction noise on a CAD part can read impulsive (``γ̂_rms > 1.3 γ̂``: the creases'
    curvature in the umbrella Laplacian, and the heavier tail of a Gaussian times the cosine of
    a random direction), so :func:`fidelity_data` alone would give it the unfolded data; this
    rule gives it the input. Inputs that do not read impulsive, or whose noise lies along the
    normals, are not affected (docs/parameters.md).
    """
    if not (impulsive and UNFOLD_DATA_IMPULSIVE):
        return False
    if support_fraction < UNFOLD_DATA_CAD_SUPPORT:  # r_t is not read as a direction here
        return True
    return bool(tangential < UNFOLD_DATA_TANGENTIAL_MAX)


UNFOLD_RESULT = True
"""Faces still folded over in the *result* are unfolded by the same umbrella step as the input,
cluster by cluster where the unfolded faces agree better with the robust probe's normals
(:func:`unfold_result`). With the input as data (:func:`fidelity_data`), a fold of the input on
a coarse mesh can survive both solves, and each folded face carries a normal error of
60-180°, so a few dozen folds can make a third of the MSAE. The per-cluster check against
the probe keeps true spikes, whose faces meet at more than 90° in the truth too
(docs/parameters.md)."""


def unfold_result(V_out: np.ndarray, topo, V_ref: np.ndarray | None = None
                  ) -> tuple[np.ndarray, int]:
    """The result with its locally folded faces unfolded.

    A face *f* is folded when ``⟨n_f, Σ_g n_g⟩ ≤ 0`` over its edge-neighbours *g*
    (:func:`meshrepair.model.relax.locally_flipped_faces`); the vertices of folded faces and their
    1-ring are moved to their neighbours' centroid until no face is folded
    (:func:`meshrepair.model.relax.untangle`, which keeps the iterate with the fewest folds, so a
    fold it cannot remove leaves the result unchanged). Vertices away from folds do not move.

    With a reference ``V_ref`` (``denoise`` passes the robust probe's result, which has no
    folds and keeps true spikes), each connected cluster K of moved vertices keeps its unfolded
    positions only when the faces touching it then agree better with the reference normals:

    .. math:: \\sum_{f \\sim K} \\angle(n_f(V_u), n_f(V_{ref}))
              < \\sum_{f \\sim K} \\angle(n_f(V_{out}), n_f(V_{ref})),

    so a true spike whose faces meet at more than 90° is not blunted.

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

    from meshrepair.mesh.geometry import face_normals

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


COLLAPSE_VOLUME_RATIO = 0.5
"""A closed mesh whose enclosed volume falls below this fraction of the input's is collapsed:
with the defaults on the closed benchmark meshes at γ = 0.3 (normal and random directions) the
ratio stays within 1 % of 1, while the robust stage can flatten a tetrahedron with γ = 0.1 to
1 % of its volume; 0.5 lies far from both."""


def _volume_ratio(V: np.ndarray, V_out: np.ndarray, F: np.ndarray, report) -> float | None:
    """Signed volume of the result over the input's, for a closed mesh with a clear volume
    (``|vol| > 1e-6 diag³``); None otherwise."""
    if not report.is_closed or len(F) == 0:
        return None

    from meshrepair._kernels.faces import signed_volume

    c = V.mean(axis=0)
    v_in = signed_volume(V, F, c)
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    if not np.isfinite(v_in) or abs(v_in) <= 1e-6 * diag**3:
        return None
    return signed_volume(V_out, F, c) / v_in


REINTEGRATE_FOLD_CHECK_RATIO = 0.3
"""Tangential ratio ``ρ_t^after`` above which the re-integration from the input is checked for
folds the input put back (:func:`reintegration_keeps`)."""


def reintegration_keeps(ratio_after: float, folded_result: int, folded_target: int) -> bool:
    """Whether the re-integration from the input (:func:`meshrepair.denoise.organic.reintegrate`,
    is kept:

    .. math:: \\text{keep} \\iff ρ_t^{after} \\le 0.3 \\;\\vee\\;
              |\\mathcal{F}(X)| \\le |\\mathcal{F}(X_g)|,

    ``X`` the re-integrated vertices, ``X_g`` the guidance result whose face normals ``n*`` they
    were fitted to, ``𝓕`` the folded faces (:func:`meshrepair.model.relax.locally_flipped_faces`).

    The Sun et al. steps move each vertex along the target normals only, so ``X`` keeps the
    input's tangential offset ``t_i = P_i(V⁰_i − V_i)`` from the re-anchored result ``V``, and
    ``ρ_t^after = rms‖t‖ / rms⟨V⁰ − V, n⟩`` measures it. Noise along the normals that the
    solve removed leaves a small ``t`` (the result's own drift, about 0.14-0.19), and then the
    input's layout is the better one. A larger ``t`` may be the input's own tangential noise
    (random-direction noise reads 0.33-0.52) or the drift around thrown vertices (impulsive
    noise along the normals, about 0.3). The two differ in
    what the steps do: on a flat patch all target normals are equal, so a step cannot move a
    vertex within the plane, and every face the tangential noise folded over in that plane
    stays folded, a 180° normal error each. Folds the target does not have are therefore read
    as the input's tangential noise put back, and ``X_g`` is kept; thrown vertices along the
    normals fold no in-plane face (``X`` has no more folds than ``X_g``), so their
    re-integration stays.
    """
    if not ratio_after > REINTEGRATE_FOLD_CHECK_RATIO:
        return True
    return int(folded_result) <= int(folded_target)
