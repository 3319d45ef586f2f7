"""Cuts merged with a mesh's own open border (issue 28): what splitting the merged loop gives.

A disc of the cut protocol (``benchmarks/holes.py --cases protocol``) that reaches a mesh's own
open border (a statue's open base) leaves ONE boundary loop: the border's arcs and the cut's
arcs. This benchmark knows which loop vertices lay on the uncut mesh's border (vertex identity),
so it finds the *junctions* (a border vertex next to a cut vertex) without any rule, and
compares, per (mesh, r, seed) whose cut merged with the border:

* ``whole``: ``fill_holes`` on the cut mesh (the merged loop filled as one patch);
* ``split, border open``: every cut arc closed by the straight chord between its two junctions
  (vertices spaced one mean edge length l̄), the border part (border arcs + chords) capped by a
  temporary planar patch, ``fill_holes`` on that mesh (the cut parts are then loops of their
  own), the temporary cap removed: the cut parts filled, the border part left open;
* ``split, border filled``: the same, then ``fill_holes`` fills the border part too.

Figures as the protocol's: new faces within ``1.5 r + 2`` l̄ of a cut centre against the removed
faces, mean symmetric distance (×1e-3 of the diagonal) and mean normal deviation; the runs whose
cut does not meet the border are the same in every variant and are not rerun.

Usage: ``python benchmarks/holes_merged.py --mesh nicolo --radii 4,8,16,24 --seeds 0,1,2``
"""

from __future__ import annotations

import argparse
import json

import _common
import _holes_peers as hp
import numpy as np
from scipy.spatial import cKDTree

from meshrepair.fill import fill_holes
from meshrepair.holes import _find_holes, enclose_loop
from meshrepair.mesh.geometry import mean_edge_length
from meshrepair.mesh.topology import boundary_loops
from meshrepair.synthetic import cut_holes


def split_border_part(Vc: np.ndarray, loop: np.ndarray, on_border: np.ndarray, le: float):
    """The border part of a merged loop: its border arcs joined by straight chords across each
    cut arc. Returns ``(Vw, part)``: the positions with the chord vertices appended and the
    border part's vertex list (loop order)."""
    n = len(loop)
    k0 = int(np.flatnonzero(on_border & ~np.roll(on_border, -1))[0])
    lp, b = np.roll(loop, -k0), np.roll(on_border, -k0)
    Vw = Vc.copy()
    part: list[int] = []
    i = 0
    while i < n:
        if b[i] and i + 1 < n and not b[i + 1]:
            j = i + 1
            while not b[j % n]:
                j += 1
            a, c = lp[i], lp[j % n]
            m = max(int(round(np.linalg.norm(Vw[c] - Vw[a]) / le)) - 1, 0)
            t = np.linspace(0.0, 1.0, m + 2)[1:-1]
            part += [int(a)] + list(range(len(Vw), len(Vw) + m))
            Vw = np.r_[Vw, Vw[a] + t[:, None] * (Vw[c] - Vw[a])]
            i = j
        else:
            part.append(int(lp[i]))
            i += 1
    return Vw, np.asarray(part, np.int64)


def _drop_faces(V: np.ndarray, F: np.ndarray, faces: np.ndarray):
    """``(V, F)`` without the faces equal (as vertex sets) to rows of ``faces``, unused vertices
    dropped."""
    gone = set(map(tuple, np.sort(faces, axis=1).tolist()))
    keep = np.array([tuple(f) not in gone for f in np.sort(F, axis=1).tolist()])
    F = F[keep]
    used = np.zeros(len(V), bool)
    used[F.ravel()] = True
    idx = -np.ones(len(V), np.int64)
    idx[used] = np.arange(used.sum())
    return V[used], idx[F]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mesh", default="nicolo")
    ap.add_argument("--radii", default="4,8,16,24")
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--jsonl", default=None)
    args = ap.parse_args()
    _common.limit_threads(1)
    V, F, _ = _common.read(args.mesh)
    le = mean_edge_length(V, F)
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    loops = boundary_loops(F, len(V))
    border = np.unique(np.concatenate(loops)) if loops else np.empty(0, np.int64)
    fh = open(args.jsonl, "a") if args.jsonl else None  # noqa: SIM115
    for r in [float(x) for x in args.radii.split(",")]:
        for seed in [int(x) for x in args.seeds.split(",")]:
            Vc, Fc, removed, centres = cut_holes(V, F, r, seed=seed)
            keep = np.zeros(len(V), bool)
            keep[np.unique(F[np.setdiff1d(np.arange(len(F)), removed)])] = True
            on_b = np.isin(np.flatnonzero(keep), border)
            merged = [h for h in _find_holes(Vc, Fc)
                      if on_b[h.vertices].any() and not on_b[h.vertices].all()]
            if not merged:
                continue

            def metric(Vo, Fo, Vc=Vc, Fc=Fc, removed=removed, centres=centres, r=r):
                new = hp.new_faces(Vc, Fc, Vo, Fo)
                d, _ = cKDTree(V[centres]).query(Vo[Fo[new]].mean(axis=1))
                m, _, nd, _, _, _ = hp.measure(V, F[removed], V, F, Vo, Fo,
                                               new[d <= 1.5 * r * le + 2 * le], diag, le)
                return m * 1e3, nd

            rec = {"mesh": args.mesh, "r": r, "seed": seed,
                   "merged": [[int(h.n_boundary), int(on_b[h.vertices].sum())] for h in merged]}
            rec["whole"] = metric(*_fill(Vc, Fc))
            Vw, Fw, caps = Vc, Fc, []
            for h in merged:
                if h.n_boundary - on_b[h.vertices].sum() < 3:
                    continue  # a sliver of the border, not a cut arc
                Vw, part = split_border_part(Vw, h.vertices, on_b[h.vertices], le)
                pt = enclose_loop(Vw[part], edge_length=le)
                loc = np.r_[part, np.arange(len(Vw), len(Vw) + len(pt.X) - len(part))]
                Vw = np.r_[Vw, pt.X[len(part):]]
                caps.append(loc[pt.T])
                Fw = np.r_[Fw, loc[pt.T]]
            V1, F1 = _fill(Vw, Fw)
            V2, F2 = _drop_faces(V1, F1, np.concatenate(caps))
            rec["split, border open"] = metric(V2, F2)
            rec["split, border filled"] = metric(*_fill(V2, F2))
            print(json.dumps(rec), flush=True)
            if fh:
                fh.write(json.dumps(rec) + "\n")
    if fh:
        fh.close()


def _fill(V, F):
    r = fill_holes(V, F)
    return r.V, r.F


if __name__ == "__main__":
    main()
