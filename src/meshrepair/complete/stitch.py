"""Stitching a template into a hole: ring distances, ears, harmonic spreading (Sect. 5).

:func:`stitch_template` does the suitable subdivision of both loops and the stitching of
:func:`meshrepair.complete` (steps 4 and 5 of its docstring). Helpers that work on the
two meshes being joined:
edge-ring distances to a vertex set (:func:`_rings`), splitting template faces that own two
boundary edges (:func:`_split_ears`), spreading the seam gap over the template's first rings
(:func:`_harmonic_displacement`), and converting split fractions between a loop and its
reversed sequence (:func:`_to_loop_params`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from meshrepair.complete.loopmatch import align_loops, monotone_loop_match
from meshrepair.complete.rigid import apply_transform
from meshrepair.errors import MeshRepairError
from meshrepair.mesh.geometry import vertex_normals
from meshrepair.mesh.topology import boundary_loops, edge_topology, vertex_adjacency

log = logging.getLogger(__name__)


def degenerate_seam_error(n: int) -> MeshRepairError:
    """The error for a stitch that would create ``n`` zero-area faces (raised by
    :func:`stitch_template`, and up front by :func:`meshrepair.complete.inputs._check_template`
    for a template that is degenerate already)."""
    return MeshRepairError(
        f"stitching the template into the hole gives {n} zero-area faces (template faces whose "
        "corners land on collinear seam vertices); subdivide the template near its boundary, or "
        "choose a slightly different region")


def _to_loop_params(params_seq: list[np.ndarray], reversed_seq: bool) -> list[np.ndarray]:
    """Convert split fractions given along a sequence to the loop's own edge order."""
    if not reversed_seq:
        return params_seq
    n = len(params_seq)
    out: list[np.ndarray] = [np.zeros(0)] * n
    for i, t in enumerate(params_seq):
        # sequence = loop[::-1]: its edge i is loop edge (n - 2 - i) % n traversed backwards
        out[(n - 2 - i) % n] = np.sort(1.0 - np.asarray(t))
    return out


def _rings(topo, seeds: np.ndarray, max_ring: int) -> np.ndarray:
    """Edge-ring distance of every vertex to ``seeds`` (``max_ring + 1`` beyond ``max_ring``)."""
    nV = topo.n_vertices
    A = vertex_adjacency(topo.edges, nV)
    dist = np.full(nV, max_ring + 1, dtype=np.int64)
    dist[seeds] = 0
    front = np.zeros(nV)
    front[seeds] = 1.0
    for r in range(1, max_ring + 1):
        reach = (A @ front > 0) & (dist > max_ring)
        if not reach.any():  # every reachable vertex has its ring: the rest stay beyond
            break
        dist[reach] = r
        front = reach.astype(np.float64)
    return dist


def _split_ears(V: np.ndarray, F: np.ndarray, loop: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, int]:
    """Split the inner edge of every face that owns two edges of the boundary ``loop``.

    Such an *ear* would become a zero-area face if its three boundary vertices were merged into
    three collinear seam vertices (which happens when ``b0``'s edges are subdivided). The inner
    edge ``(a, b)`` is split at its midpoint ``m`` and both faces containing it are split in two
    (``(a, b, c) -> (a, m, c), (m, b, c)``), which keeps the surface and the orientation.

    Returns
    -------
    V2, F2 : the patch with the new vertices appended
    n_split : number of ears split
    """
    n = len(loop)
    bedges = {(int(loop[i]), int(loop[(i + 1) % n])) for i in range(n)}
    Fl = F.tolist()
    he_face = {}
    for fi, (a, b, c) in enumerate(Fl):
        he_face[(a, b)] = fi
        he_face[(b, c)] = fi
        he_face[(c, a)] = fi
    ears = [fi for fi, (a, b, c) in enumerate(Fl)
            if ((a, b) in bedges) + ((b, c) in bedges) + ((c, a) in bedges) == 2]
    if not ears:
        return V, F, 0
    Vl = [V]
    nxt = len(V)
    for fi in ears:
        a, b, c = Fl[fi]
        he = [(a, b), (b, c), (c, a)]
        u, v = next(h for h in he if h not in bedges)  # the inner edge
        m = nxt
        nxt += 1
        Vl.append(0.5 * (V[u] + V[v])[None, :])
        for x, y in ((u, v), (v, u)):  # both faces on the edge
            fj = he_face.pop((x, y), None)
            if fj is None:
                continue
            f = Fl[fj]
            k = f.index(x)
            z = f[(k + 2) % 3]
            Fl[fj] = [x, m, z]
            Fl.append([m, y, z])
            fn = len(Fl) - 1
            he_face[(x, m)] = fj
            he_face[(m, z)] = fj
            he_face[(m, y)] = fn
            he_face[(y, z)] = fn
            he_face[(z, x)] = fj
    return np.vstack(Vl), np.asarray(Fl, dtype=np.int64), len(ears)


def _harmonic_displacement(V: np.ndarray, F: np.ndarray, loop: np.ndarray, disp: np.ndarray,
                           rings: int) -> np.ndarray:
    """Spread a displacement of the boundary ``loop`` over ``rings`` rings of a patch.

    The displacement is ``disp`` on the loop, 0 on the vertices more than ``rings`` rings away,
    and harmonic (uniform graph Laplacian) in between. Returns ``(nV, 3)``.
    """
    from scipy.sparse.linalg import spsolve

    topo = edge_topology(F, len(V))
    dist = _rings(topo, loop, rings + 1)
    D = np.zeros((len(V), 3))
    D[loop] = disp
    inner = np.flatnonzero((dist >= 1) & (dist <= rings))
    if inner.size == 0 or rings < 1:
        return D
    Adj = vertex_adjacency(topo.edges, len(V)).tocsr()
    deg = np.asarray(Adj.sum(axis=1)).ravel()
    L = (sp.diags(deg) - Adj).tocsr()
    L_ii = L[inner][:, inner].tocsc()
    rhs = -(L[inner] @ D)
    D[inner] = np.asarray(spsolve(L_ii, rhs)).reshape(-1, 3)
    return D


@dataclass
class Stitched:
    """Result of :func:`stitch_template`.

    Attributes
    ----------
    V_init, F_star : the stitched mesh ``V^(0)``, ``T*`` (see ``complete`` for the order)
    seam : (n,) int64, ``b0`` after subdivision, in the stitched mesh
    new_index : (nV + inserted,) int64, new index of each vertex of the subdivided mesh (-1:
        removed)
    n_mesh : int, vertices kept from the mesh (the template's interior vertices follow)
    gap_l : (n,) float64, normal seam gap per seam vertex, in mean edge lengths
    max_gap, rms_after : float, largest and RMS distance of the paired seam points
    inserted_region, inserted_template, ears_split : int
    """

    V_init: np.ndarray
    F_star: np.ndarray
    seam: np.ndarray
    new_index: np.ndarray
    n_mesh: int
    gap_l: np.ndarray
    max_gap: float
    rms_after: float
    inserted_region: int
    inserted_template: int
    ears_split: int


def stitch_template(V: np.ndarray, F: np.ndarray, region_faces: np.ndarray, removed: np.ndarray,
                    b0: np.ndarray, VP: np.ndarray, FP: np.ndarray, bP: np.ndarray,
                    T: np.ndarray, rev: bool, *, strip_rings: int, hole: bool,
                    unit: float) -> Stitched:
    """Subdivide both loops to a common sampling and stitch the placed template into the hole.

    Parameters
    ----------
    V, F : the mesh; region_faces : faces removed; removed : (nV,) bool, vertices removed
    b0 : the hole's loop (remaining faces' orientation)
    VP, FP, bP : the template and its loop; T : (4, 4), its placement
    rev : the template loop runs against ``b0`` (no face flip needed)
    strip_rings : rings of the template over which the seam gap is spread
    hole : an existing hole is completed (one boundary loop fewer expected)
    unit : mean edge length (for ``gap_l``)
    """
    from meshrepair.complete.correspondence import split_boundary_edges
    from meshrepair.mesh.validate import check_mesh

    flipped = not rev
    nV, nF = len(V), len(F)
    A = V[b0]
    Fm = F[np.setdiff1d(np.arange(nF), region_faces)] if region_faces.size else F.copy()
    bseq = bP[::-1] if rev else bP
    VPt = apply_transform(T, VP)
    la = align_loops(A, VPt[bseq])
    Vm, Fm, b0_2, new = split_boundary_edges(V, Fm, b0, la.params_A)
    ins_region = len(new)
    VP2, FP2, bP2, new = split_boundary_edges(VPt, FP, bP, _to_loop_params(la.params_B, rev))
    ins_template = len(new)
    VP2, FP2, n_ears = _split_ears(VP2, FP2, bP2)
    bseq2 = bP2[::-1] if rev else bP2
    match, rms_after = monotone_loop_match(Vm[b0_2], VP2[bseq2])
    pairs_t = bseq2[match]  # template vertex matched with b0_2[i]
    gap = Vm[b0_2] - VP2[pairs_t]
    max_gap = float(np.linalg.norm(gap, axis=1).max())
    # move the template's border so that b_P lands on b0 without folding its first faces
    VP2 = VP2 + _harmonic_displacement(VP2, FP2, pairs_t, gap, strip_rings)

    keep = np.ones(len(Vm), bool)
    keep[:nV] = ~removed
    new_index = np.cumsum(keep) - 1
    new_index[~keep] = -1
    n_mesh = int(keep.sum())
    tmap = np.full(len(VP2), -1, dtype=np.int64)
    tmap[pairs_t] = new_index[b0_2]
    interior = tmap < 0
    tmap[interior] = n_mesh + np.arange(int(interior.sum()))
    FPn = tmap[FP2]
    if flipped:
        FPn = FPn[:, [0, 2, 1]]
    V_init = np.vstack([Vm[keep], VP2[interior]])
    F_star = np.vstack([new_index[Fm], FPn]).astype(np.int64)
    seam = new_index[b0_2]
    n_loops_in = len(boundary_loops(F, nV))
    try:
        rep = check_mesh(V_init, F_star, name="completed mesh", allow_degenerate=True)
    except MeshRepairError as exc:
        raise MeshRepairError(
            f"stitching the template into the hole gives an invalid mesh ({exc}); this happens "
            "when the template has faces or edges joining boundary vertices that the mesh "
            "already joins: subdivide the template near its boundary or enlarge the region"
        ) from None
    n_loops_out = len(boundary_loops(F_star, len(V_init)))
    expected = n_loops_in - (1 if hole else 0)
    if n_loops_out != expected:
        log.warning("the completed mesh has %d boundary loops (input %d)", n_loops_out,
                    n_loops_in)
    if rep.n_degenerate_faces:
        raise degenerate_seam_error(rep.n_degenerate_faces)
    if rep.n_pinched_vertices:
        log.warning("the completed mesh has %d pinched vertices", rep.n_pinched_vertices)
    log.info("stitched: %d vertices (%d inserted on b0, %d on b_P), %d faces, seam RMS %.3g",
             len(V_init), ins_region, ins_template, len(F_star), rms_after)

    # the seam's step across the surface: the gap along the remaining surface's normal at b0
    # (a tangential gap, e.g. two tessellations of one surface, needs no blending)
    n_seam = vertex_normals(Vm, Fm)[b0_2]
    gap_l = np.abs(np.einsum("ij,ij->i", gap, n_seam)) / unit
    return Stitched(V_init=V_init, F_star=F_star, seam=seam, new_index=new_index, n_mesh=n_mesh,
                    gap_l=gap_l, max_gap=max_gap, rms_after=float(rms_after),
                    inserted_region=ins_region, inserted_template=ins_template,
                    ears_split=n_ears)
