"""The cut protocol against peers on every shared real mesh (issue 28): used by
``benchmarks/holes.py --cases protocol``.

For every mesh, radius r (in mean edge lengths l̄) and seed: :func:`meshrepair.synthetic.cut_holes`
cuts 3 geodesic discs (random centres kept 2.5 r apart; the first disc of a CAD mesh is centred
on a crease vertex, :func:`_holes_peers.pick_centres`), every method fills the cut mesh, and the
new faces near the cuts (centroid within ``1.5 r l̄ + 2 l̄`` of a centre, so a peer's fill of a
mesh's own real holes or open border is not counted) are compared with the removed faces:
symmetric mean distance / bounding-box diagonal and mean normal deviation
(:func:`_holes_peers.measure`), the same mean with every sample weighted by the area it stands
for (:func:`area_weighted_mean`), wall time and resident-memory high-water mark above the RSS
before the fill. Holes a method leaves open count as not filled (``filled`` column: cut loops
closed / cut loops); meshrepair's records also list its skipped loops and notes (``notes``).

Peers: CGAL refine-and-fair, MeshLib ``fillHole`` (minimum-area triangulation, no refinement)
and ``fillHoleNicely``, PyMeshLab ``meshing_close_holes`` (refined, every hole), pymeshfix.
"""

from __future__ import annotations

import json
import time

import _common
import _holes_peers as hp
import numpy as np
from scipy.spatial import cKDTree

from meshrepair.mesh.geometry import mean_edge_length
from meshrepair.mesh.topology import boundary_loops
from meshrepair.metrics import point_to_surface
from meshrepair.synthetic import cut_holes

CAD = ("fandisk", "twelve", "sharp_sphere", "trim_star", "rocker_arm", "screwdriver")
ORGANIC = ("spot", "bunny", "nicolo", "camelhead", "nefertiti", "igea")


_BARY = np.array([(1 / 3, 1 / 3, 1 / 3), (2 / 3, 1 / 6, 1 / 6), (1 / 6, 2 / 3, 1 / 6),
                  (1 / 6, 1 / 6, 2 / 3)])


def _area_samples(V, F):
    """Four barycentric points per face and the area each stands for (a quarter of its face's)."""
    T = V[F]
    area = 0.5 * np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    return np.einsum("kb,fbd->fkd", _BARY, T).reshape(-1, 3), np.repeat(area / 4, 4)


def area_weighted_mean(V, F, V_ref, F_ref) -> float:
    """Symmetric mean surface distance between two meshes with every sample weighted by the area
    it stands for: ``(∫_P d(x, G) dA / |P| + ∫_G d(y, P) dA / |G|) / 2``. The ``mean`` of
    :func:`meshrepair.metrics.distances` counts vertices and a fixed number of points per face
    alike, so a region of a patch weighs by its number of faces: a patch with large triangles
    where it is far from the truth (or where there is no truth, as over an open border merged
    with a cut) weighs that region less than a patch of uniform density."""
    p, wp = _area_samples(V, F)
    g, wg = _area_samples(V_ref, F_ref)
    if wp.sum() <= 0 or wg.sum() <= 0:
        return float("nan")
    a = point_to_surface(p, V_ref, F_ref)
    b = point_to_surface(g, V, F)
    return float(0.5 * ((a * wp).sum() / wp.sum() + (b * wg).sum() / wg.sum()))


def _meshlib_plain(V, F, hc):
    import meshlib.mrmeshnumpy as mn
    import meshlib.mrmeshpy as mm

    m = mn.meshFromFacesVerts(np.ascontiguousarray(F, np.int32), np.ascontiguousarray(V))
    for e in list(m.topology.findHoleRepresentiveEdges()):
        mm.fillHole(m, e, mm.FillHoleParams())
    m.pack()
    return (np.asarray(mn.getNumpyVerts(m), float),
            np.asarray(mn.getNumpyFaces(m.topology), np.int64))


def _pymeshlab(V, F, hc):
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(np.ascontiguousarray(V, float), np.ascontiguousarray(F, np.int32)))
    ms.meshing_close_holes(maxholesize=100000, refinehole=True,
                           refineholeedgelen=pymeshlab.PureValue(float(hc)))
    m = ms.current_mesh()
    return np.asarray(m.vertex_matrix(), float), np.asarray(m.face_matrix(), np.int64)


METHODS = {"meshrepair": hp._meshrepair, "CGAL refine+fair": hp._cgal,
           "MeshLib fillHole": _meshlib_plain, "MeshLib fillHoleNicely": hp._meshlib,
           "PyMeshLab close_holes": _pymeshlab, "pymeshfix": hp._pymeshfix}


def _cut_loops_closed(Vc, Fc, Vo, Fo, cut_vertices) -> tuple[int, int]:
    """(cut loops closed, cut loops): a cut loop is closed when none of its vertices is on a
    boundary loop of the output (vertices matched by position)."""
    loops = [lp for lp in boundary_loops(Fc, len(Vc)) if np.isin(lp, cut_vertices).any()]
    if not loops:
        return 0, 0
    out_b = np.unique(np.concatenate(boundary_loops(Fo, len(Vo)) or [np.empty(0, np.int64)]))
    diag = float(np.linalg.norm(np.ptp(Vc, axis=0)))
    open_pos = Vo[out_b] if len(out_b) else np.empty((0, 3))
    tree = cKDTree(open_pos) if len(open_pos) else None
    closed = 0
    for lp in loops:
        if tree is None or (tree.query(Vc[lp])[0] > 1e-6 * diag).all():
            closed += 1
    return closed, len(loops)


def run_protocol(lines: list[str], notes: list[str], meshes, radii, seeds, out_jsonl=None,
                 methods=None, budget_s: float = float("inf")) -> list[dict]:
    """Run the protocol; one JSON record per (mesh, r, seed, method), printed as it comes."""
    avail = hp.available(notes)
    names = [m for m in (methods or METHODS) if m in METHODS]
    for extra in ("MeshLib fillHole", "PyMeshLab close_holes"):
        mod = "meshlib.mrmeshpy" if extra.startswith("MeshLib") else "pymeshlab"
        try:
            __import__(mod)
            avail[extra] = METHODS[extra]
        except Exception as exc:  # noqa: BLE001
            notes.append(f"{extra} skipped: cannot import {mod} ({exc!r})")
    recs: list[dict] = []
    t_start = time.perf_counter()
    fh = open(out_jsonl, "a") if out_jsonl else None  # noqa: SIM115
    for name in meshes:
        V, F, _ = _common.read(name)
        le = mean_edge_length(V, F)
        diag = float(np.linalg.norm(np.ptp(V, axis=0)))
        first = [c for k, c in hp.pick_centres(V, F) if k == "crease"] if name in CAD else []
        for r in radii:
            for seed in seeds:
                if time.perf_counter() - t_start > budget_s:
                    notes.append(f"time budget reached before {name} r={r} seed={seed}")
                    return recs
                keep = np.zeros(len(V), bool)
                Vc, Fc, removed, centres = cut_holes(V, F, r, seed=seed, centres=first)
                keep[np.unique(F[np.setdiff1d(np.arange(len(F)), removed)])] = True
                idx = -np.ones(len(V), np.int64)
                idx[keep] = np.arange(keep.sum())
                cut_v = np.unique(idx[F[removed]][idx[F[removed]] >= 0])
                for m in names:
                    if m not in avail:
                        continue
                    _common.reset_peak_rss()
                    base = _common.rss_now_mb()
                    t = time.perf_counter()
                    try:
                        Vo, Fo = avail[m](Vc, Fc, le)
                        err = None
                    except Exception as exc:  # noqa: BLE001
                        err = repr(exc)[:80]
                    dt = time.perf_counter() - t
                    peak = _common.peak_rss_mb() - base
                    rec = {"mesh": name, "kind": "CAD" if name in CAD else "organic", "r": r,
                           "seed": seed, "method": m, "t": dt, "mem_mb": peak}
                    if err is None:
                        new = hp.new_faces(Vc, Fc, Vo, Fo)
                        cen = Vo[Fo[new]].mean(axis=1) if len(new) else np.empty((0, 3))
                        near = np.zeros(len(new), bool)
                        if len(new):
                            d, _ = cKDTree(V[centres]).query(cen)
                            near = d <= 1.5 * r * le + 2 * le
                        mm, _, nd, _, _, _ = hp.measure(V, F[removed], V, F, Vo, Fo, new[near],
                                                        diag, le)
                        c, n = _cut_loops_closed(Vc, Fc, Vo, Fo, cut_v)
                        ma = (area_weighted_mean(Vo, Fo[new[near]], V, F[removed]) / diag
                              if near.any() else float("nan"))
                        rec.update(mean=mm, mean_area=ma, normal=nd, closed=c, loops=n)
                        if m == "meshrepair" and hp.LAST_NOTES:
                            rec["notes"] = list(hp.LAST_NOTES)
                    else:
                        rec["error"] = err
                    recs.append(rec)
                    if fh:
                        fh.write(json.dumps(rec) + "\n")
                        fh.flush()
                    print(json.dumps(rec), flush=True)
    if fh:
        fh.close()
    lines.extend(table(recs))
    return recs


def table(recs: list[dict]) -> list[str]:
    """Markdown table: per (mesh, r) and method, the mean over seeds of the patch distance
    (×1e-3 of the diagonal; with records that carry it, the area-weighted one too), the normal
    deviation, time, memory and the cut loops closed; then meshrepair against the best peer on
    each figure."""
    aw = any("mean_area" in x for x in recs)  # area-weighted mean in the records
    out = ["| mesh | r (l̄) | method | seeds | mean e-3 | " + ("area-w e-3 | " if aw else "")
           + "normal° | t s | MB | closed |",
           "|---|---:|---|---:|---:|" + ("---:|" if aw else "") + "---:|---:|---:|---|"]
    keys = sorted({(r["mesh"], r["r"]) for r in recs}, key=lambda k: (k[0], k[1]))
    ratio_rows = ["", "| mesh | r (l̄) | meshrepair mean / best peer (who) | "
                  + ("meshrepair area-w / best peer (who) | " if aw else "")
                  + "meshrepair normal / best peer (who) |",
                  "|---|---:|---|---|" + ("---|" if aw else "")]
    for mesh, r in keys:
        best_m, best_n, best_a = (np.inf, ""), (np.inf, ""), (np.inf, "")
        ours = None
        for m in METHODS:
            rs = [x for x in recs if x["mesh"] == mesh and x["r"] == r and x["method"] == m]
            if not rs:
                continue
            ok = [x for x in rs if "mean" in x and np.isfinite(x["mean"])]
            mean = float(np.mean([x["mean"] for x in ok])) if ok else float("nan")
            nd = float(np.mean([x["normal"] for x in ok])) if ok else float("nan")
            ma = float(np.mean([x.get("mean_area", np.nan) for x in ok])) if ok else float("nan")
            c = sum(x.get("closed", 0) for x in rs)
            n = sum(x.get("loops", 0) for x in rs)
            fails = sum("error" in x for x in rs)
            out.append(f"| {mesh} | {r} | {m} | {len(rs)} | {mean * 1e3:.3f} | "
                       + (f"{ma * 1e3:.3f} | " if aw else "") + f"{nd:.2f} | "
                       f"{np.mean([x['t'] for x in rs]):.2f} | "
                       f"{np.mean([x['mem_mb'] for x in rs]):.0f} | {c}/{n}"
                       f"{f', {fails} failed' if fails else ''} |")
            if m == "meshrepair":
                ours = (mean, nd, ma)
            elif ok:
                if mean < best_m[0]:
                    best_m = (mean, m)
                if ma < best_a[0]:
                    best_a = (ma, m)
                if nd < best_n[0]:
                    best_n = (nd, m)
        if ours is not None and np.isfinite(best_m[0]):
            area = (f"{ours[2] / best_a[0]:.2f}× ({best_a[1]}) | " if np.isfinite(best_a[0])
                    else "- | ") if aw else ""
            ratio_rows.append(f"| {mesh} | {r} | {ours[0] / best_m[0]:.2f}× ({best_m[1]}) | "
                              + area + f"{ours[1] / best_n[0]:.2f}× ({best_n[1]}) |")
    return out + ratio_rows
