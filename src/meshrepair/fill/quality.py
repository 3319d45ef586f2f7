"""Per-hole quality read-out of the final patches: how the patch meets its surround (seam angle
against the surround's own dihedral angles) and how curved it is against the surround (mean
curvature ratio), so a user sees which fills to check.

For a filled hole with patch faces ``P``:

* ``seam_deg``: mean dihedral angle across the loop edges (one patch face, one original face);
* ``surround_deg``: mean dihedral angle of the original edges within 3 rings of the patch;
* ``curvature_ratio``: ``(mean |H̄| over the patch's interior vertices + κ0) / (mean |H̄| over
  the original vertices within 3 rings, loop and mesh-boundary vertices excluded, + κ0)``,
  ``κ0 = 0.01 / l̄`` (a radius of 100 edge lengths: a flat patch in a flat surround has ratio
  1, not 0/0). ``H̄`` is the cotangent mean curvature ``H`` low-passed by
  :data:`CURVATURE_SMOOTHING` umbrella averages, each over the neighbours on the same side of
  the seam (original vertices with original ones, new with new: the patch and its surround
  are read apart): ``|H|`` of a noisy scan is mostly its noise, which the mean of a
  magnitude does not cancel, so without the low-pass a smooth patch in a raw scan reads as a
  fraction as curved as its surround; averaged over 3 rings (the surround's width),
  zero-mean noise cancels and the shape's curvature stays. A patch continuing its surround
  has a ratio near 1 and a seam angle near the surround's.
* ``check``: True when ``seam_deg > SEAM_CHECK_FACTOR * surround_deg + SEAM_CHECK_MARGIN`` or
  the ratio is outside ``[1 / CURVATURE_CHECK, CURVATURE_CHECK]``; ``why`` says which.
"""

from __future__ import annotations

import numpy as np

from meshrepair.fill.patches import _blocks, _seam_angle
from meshrepair.holes import HoleReport

SEAM_CHECK_FACTOR = 2.0
SEAM_CHECK_MARGIN = 5.0
"""A seam sharper than ``SEAM_CHECK_FACTOR * surround + SEAM_CHECK_MARGIN`` degrees is flagged."""

CURVATURE_SMOOTHING = 3
"""Umbrella averages of the mean curvature before its magnitude is read (the surround's width
in rings)."""

CURVATURE_CHECK = 2.0
"""A patch more than this many times as curved as its surround (or less than its inverse) is
flagged."""


def hole_quality(V: np.ndarray, F: np.ndarray, reports: list[HoleReport], nV: int,
                 nF: int) -> None:
    """Set ``HoleReport.quality`` of every filled hole (see the module docstring); ``nV, nF``:
    the number of original vertices and faces (the patches follow them)."""
    from meshrepair.mesh.geometry import mean_edge_length
    from meshrepair.mesh.operators import mean_curvature
    from meshrepair.mesh.topology import edge_topology

    blocks = _blocks(reports, nV, nF)
    if not blocks:
        return
    topo = edge_topology(F, len(V))
    H = np.abs(_low_passed(mean_curvature(V, F), topo.edges, nV, CURVATURE_SMOOTHING))
    on_bnd = np.zeros(len(V), bool)
    on_bnd[topo.edges[topo.boundary].ravel()] = True
    k0 = 0.01 / max(mean_edge_length(V, F), 1e-300)
    by_rep = {r.index: r for r in reports}
    for i, (bv, bf) in blocks.items():
        rep = by_rep[i]
        seam, ring = _seam_angle(V, F, bf, nF, ring=True)
        near = np.zeros(len(V), bool)
        near[F[bf].ravel()] = True
        loop = near.copy()
        loop[bv] = False
        for _ in range(3):
            near[F[near[F].any(axis=1)].ravel()] = True
        sur = near.copy()
        sur[bv] = False
        sur[loop] = False
        sur[on_bnd] = False
        sur[nV:] = False
        hp = float(H[bv].mean()) if len(bv) else float("nan")
        hs = float(H[sur].mean()) if sur.any() else float("nan")
        ratio = (hp + k0) / (hs + k0)
        why = []
        if seam > SEAM_CHECK_FACTOR * ring + SEAM_CHECK_MARGIN:
            why.append(f"seam {seam:.1f}° against a surround of {ring:.1f}°")
        if np.isfinite(ratio) and not 1.0 / CURVATURE_CHECK <= ratio <= CURVATURE_CHECK:
            why.append(f"the patch is {ratio:.2f}× as curved as its surround")
        rep.quality = {"seam_deg": round(float(seam), 3), "surround_deg": round(float(ring), 3),
                       "curvature_ratio": round(float(ratio), 4), "check": bool(why),
                       "why": "; ".join(why)}


def _low_passed(H: np.ndarray, edges: np.ndarray, nV: int, steps: int) -> np.ndarray:
    """``H`` after ``steps`` umbrella averages ``H_i ← mean of H_j`` over the neighbours ``j`` of
    ``i`` on its side of the seam (both ``< nV``, or both ``≥ nV``); a vertex without such a
    neighbour keeps its value."""
    from meshrepair.mesh.topology import vertex_adjacency

    same = (edges[:, 0] < nV) == (edges[:, 1] < nV)
    A = vertex_adjacency(edges[same], len(H))
    deg = np.asarray(A.sum(axis=1)).ravel()
    has = deg > 0
    out = np.asarray(H, dtype=np.float64).copy()
    for _ in range(int(steps)):
        out = np.where(has, (A @ out) / np.where(has, deg, 1.0), out)
    return out


def quality_line(q: dict) -> str:
    """One line for the CLI summary."""
    if not q:
        return ""
    ratio = q["curvature_ratio"]  # none for a patch without inner vertices (one triangle)
    line = (f"seam {q['seam_deg']:.1f}° (surround {q['surround_deg']:.1f}°), curvature "
            + (f"{ratio:.2f}× the surround's" if ratio == ratio else "n/a (no inner vertex)"))
    return line + (f"; CHECK: {q['why']}" if q.get("check") else "")
