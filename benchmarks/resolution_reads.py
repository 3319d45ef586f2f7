"""What the crease network of the probe reads on the rows of ``benchmarks/resolution.py``
(issue 12): why a coarse noisy organic mesh passes the CAD test.

For each row (mesh, level, noise of ``resolution.py``'s default grid, same cached inputs) the
defaults run up to the crease-support read of the probe (the normals ``N¹`` handed to
:func:`meshrepair.denoise.crease_network.supported`, captured there; the run stops at that point),
and
the script prints: the radius ``q`` of the noisy input and of the probe in mean edge lengths,
γ̂, the supported fraction, the crease network's branching β and side spread s, and per kept
chain (longest first) its length, β_c, s_c, the persistence ratio p, the straightness
(median chord over path length between chain vertices 4 chain edges apart, on the input), the
median probe dihedral and the share of its edges whose *truth* dihedral exceeds 20°; then the
share of interior edges whose probe dihedral lies in [8°, 30°) and above 30°, and the same on the
truth. Reads the truth only for those last two columns (a diagnosis, not a rule).

    python benchmarks/resolution_reads.py                       # every mesh, dec and x1
    python benchmarks/resolution_reads.py --meshes spot trim_star --levels dec
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402, I001
import numpy as np  # noqa: E402
import resolution as R  # noqa: E402


class _Stop(Exception):
    pass


def _probe_normals(Vn, F):
    """``(topo, N¹)`` of the defaults' probe on ``(Vn, F)``."""
    from meshrepair import denoise
    from meshrepair.denoise import run as DR

    got = {}
    orig = DR._cn.supported

    def hook(topo, N, th=30.0):
        got["topo"], got["N"] = topo, np.array(N)
        raise _Stop

    DR._cn.supported = hook
    try:
        denoise(Vn, F)
    except _Stop:
        pass
    finally:
        DR._cn.supported = orig
    return got["topo"], got["N"]


def _dihedral(N, topo, idx):
    fa, fb = topo.edge_faces[idx, 0], topo.edge_faces[idx, 1]
    return np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", N[fa], N[fb]), -1.0, 1.0)))


def reads(name, level, gamma, direction, k_straight: int = 4) -> dict:
    import scipy.sparse as sp
    from scipy.sparse.csgraph import shortest_path

    from meshrepair.denoise import crease_network as cn
    from meshrepair.denoise import regions as RG
    from meshrepair.denoise.scalefree import radius_in_edges
    from meshrepair.mesh.geometry import face_normals
    from meshrepair.model.noise import noise_statistics

    V, Vn, F = R.case_inputs(name, level, gamma, direction)
    topo, N = _probe_normals(Vn, F)
    L = min(RG.MIN_CHAIN, max(1, int(np.ceil(RG.CHAIN_FRACTION * topo.n_edges))))
    cre = RG.creased_edges(topo, N, 30.0)
    ch = RG.long_chains(topo, cre, L)
    if ch.any():
        ch = RG.supported_chains(topo, N, cre, ch, long_chain=max(L, RG.LONG_CHAIN))
    sup, net = cn.supported(topo, N)
    ie = np.flatnonzero(topo.interior)
    d_p, d_t = _dihedral(N, topo, ie), _dihedral(face_normals(V, F), topo, ie)
    d_t_all = _dihedral(face_normals(V, F), topo, np.arange(topo.n_edges))
    row = dict(mesh=name, level=level, gamma=gamma, direction=direction, nV=len(V),
               q_in=radius_in_edges(Vn, F), gamma_hat=float(noise_statistics(Vn, F, topo)[0]),
               support=float(sup.mean()), beta=net.branching, spread=net.side_spread,
               band_probe=(float(np.mean((d_p >= 8) & (d_p < 30))), float(np.mean(d_p >= 30))),
               band_truth=(float(np.mean((d_t >= 8) & (d_t < 30))), float(np.mean(d_t >= 30))),
               chains=[])
    idx, g, beta, spread = cn.chain_reads(topo, N, cre, ch)
    if len(idx) == 0:
        return row
    n_c = int(g.max()) + 1
    p, _ = RG._chain_stats(RG._side_adjacency(topo, cre, len(N)), N, topo.edge_faces[idx, 0],
                           topo.edge_faces[idx, 1], g, n_c, RG.PERSIST_RINGS, RG.SIDE_RINGS)
    e = topo.edges[idx]
    nV = topo.n_vertices
    A = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(nV, nV)).tocsr()
    A = A + A.T
    lbar = float(np.linalg.norm(Vn[topo.edges[:, 0]] - Vn[topo.edges[:, 1]], axis=1).mean())
    dc = _dihedral(N, topo, idx)
    for c in np.argsort(-np.bincount(g)):
        ce = idx[g == c]
        vs = np.unique(topo.edges[ce].ravel())
        D = shortest_path(A[vs][:, vs], unweighted=True)
        ii, jj = np.nonzero(D == k_straight)
        st = (float(np.median(np.linalg.norm(Vn[vs[ii]] - Vn[vs[jj]], axis=1)))
              / (k_straight * lbar) if len(ii) else float("nan"))
        row["chains"].append(dict(n=len(ce), beta=float(beta[c]), spread=float(spread[c]),
                                  p=float(p[c]), straight=st,
                                  dihedral=float(np.median(dc[g == c])),
                                  true=float((d_t_all[ce] > 20).mean())))
    return row


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--meshes", nargs="+", default=list(R.ORGANIC + R.CAD))
    ap.add_argument("--levels", nargs="+", default=["dec", "x1"])
    a = ap.parse_args(argv)
    C.limit_threads(1)
    print("| row | nV | q | γ̂ | support | β / s | chains: len β_c s_c p str dihedral true | "
          "probe 8-30° / >30° | truth 8-30° / >30° |")
    print("|---|---:|---:|---:|---:|---|---|---|---|")
    for m in a.meshes:
        for lv in a.levels:
            for g, d in R.DEFAULT_NOISES:
                if R.case_inputs(m, lv, g, d) is None:
                    continue
                r = reads(m, lv, g, d)
                ch = "; ".join(f"{c['n']} {c['beta']:.2f} {c['spread']:.1f} {c['p']:.2f} "
                               f"{c['straight']:.2f} {c['dihedral']:.0f}° {c['true']:.2f}"
                               for c in r["chains"][:4]) or "none"
                print(f"| {m} {lv} γ{g} {d} | {r['nV']:,} | {r['q_in']:.1f} | "
                      f"{r['gamma_hat']:.3f} | {r['support']:.3f} | {r['beta']:.2f} / "
                      f"{r['spread']:.1f} | {ch} | {r['band_probe'][0]:.2f} / "
                      f"{r['band_probe'][1]:.3f} | {r['band_truth'][0]:.2f} / "
                      f"{r['band_truth'][1]:.3f} |", flush=True)


if __name__ == "__main__":
    main()
