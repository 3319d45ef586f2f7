#!/usr/bin/env python
"""Hole filling benchmark (issue 4): cut-and-refill on real meshes, the real holes of the bunny,
and fill + denoise in one solve.

Cut-and-refill: a geodesic disc (Dijkstra on the edge graph) of radius 4, 8 and 16 mean edge
lengths is cut from a closed mesh (the faces touching it are removed), refilled, and the new faces
are compared with the removed ones: symmetric mean and Hausdorff distance relative to the
bounding-box diagonal (:func:`meshrepair.metrics.distances`) and the mean angle between each
patch face normal and the normal of the nearest removed face. Cases:

* ``smooth``: spot.ply refined once by Loop subdivision (11,714 vertices), disc on the flank;
* ``CAD smooth part``: fandisk.ply, disc centred on its curved face;
* ``CAD creases``: fandisk.ply, disc centred near a corner where three sharp creases meet;
* ``bunny``: the 5 real holes of bunny.ply (no ground truth: only the seam angle, time, size).

Every case runs four variants, to show what each step contributes:

* ``flat``: the membrane of the enclosing step (harmonic, no fairing, no solve) = minimal-area-like
  flat fill;
* ``flat+ADMM``: the membrane refined by the ADMM solve (edge-Willmore on the patch);
* ``thin-plate``: the bi-Laplacian fairing with the surrounding ring as boundary data, no solve;
* ``default``: thin-plate + ADMM (what :func:`meshrepair.fill.fill_holes` does).

``seam°`` is the mean dihedral angle over the loop edges (patch against surround), ``ring°`` the
mean dihedral angle of the original edges within 3 rings of the patch (the surround's own
roughness, for comparison). ``t`` is wall seconds of
``fill_holes`` (one thread). ``method`` is the enclosing method of the patch (``plane``,
``pca-plane``, ``disc``: planar projection; ``liepa``: Liepa's minimum-weight triangulation, the
fallback when a planar patch intersects the surface).

Issue 13 cases (``benchmarks/_holes_peers.py``): ``real`` fills every shared mesh with real holes
at defaults and prints time and peak RSS; ``peers`` cuts discs from smooth meshes (radii 4, 8, 16)
and across corners and creases of CAD meshes (radii 4, 8) and refills them with meshrepair, CGAL
``triangulate_refine_and_fair_hole``, MeshLib ``fillHoleNicely`` and pymeshfix (mean/Hausdorff
patch distance, normal deviation, crease angle restored vs truth, time, peak memory);
``--crease-picture PNG`` draws docs/img/holes_crease.png.

Issue 28 (``benchmarks/_holes_protocol.py``): ``protocol`` cuts 3 discs of r = 4, 8, 16, 24 l̄
(three seeds) from every shared real mesh with :func:`meshrepair.synthetic.cut_holes` and fills
them with meshrepair, CGAL, MeshLib ``fillHole`` / ``fillHoleNicely``, PyMeshLab and pymeshfix
(``--meshes``, ``--radii``, ``--seeds``, ``--methods``, ``--jsonl`` to keep the records,
``--from-jsonl`` to print their table; ``--option KEY=VALUE`` passes a keyword to meshrepair's
``fill_holes``, e.g. ``--option triharmonic=False`` for the ablation of docs/holes.md section 5).

Usage: ``python benchmarks/holes.py [--enclose auto,liepa] [--cases cut,bunny,denoise,real,peers]``
(about a minute). ``--enclose`` sets the order in which
:data:`meshrepair.fill.options.ENCLOSE_ORDER`
tries the enclosing methods (default: the library's), e.g. ``liepa,auto`` to try Liepa's
triangulation first.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _common  # noqa: E402  (limits BLAS threads before numpy is imported)
import numpy as np  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402

from meshrepair.fill import fill_holes  # noqa: E402
from meshrepair.mesh.geometry import dihedral_angles, face_normals, mean_edge_length  # noqa: E402
from meshrepair.mesh.topology import edge_topology  # noqa: E402
from meshrepair.metrics import distances  # noqa: E402
from meshrepair.synthetic import edge_graph_distances  # noqa: E402

VARIANTS = {
    "flat": {"initial": "harmonic", "refine": False},
    "flat+ADMM": {"initial": "harmonic"},
    "thin-plate": {"initial": "bilaplacian", "refine": False},
    "default": {},
}


def cut_disc(V, F, center, radius_edges):
    inside = edge_graph_distances(V, F, center) < radius_edges * mean_edge_length(V, F)
    removed = inside[F].any(axis=1)
    Vc, Fc = compact(V, F[~removed])
    return Vc, Fc, F[removed]


def compact(V, F):
    u = np.unique(F.ravel())
    m = -np.ones(len(V), np.int64)
    m[u] = np.arange(len(u))
    return V[u], m[F]


def seam_angles(res) -> tuple[float, float]:
    """Mean dihedral angle (degrees) over the loop edges, and over the original edges within 3
    rings of the patches (the surround, for comparison)."""
    topo = edge_topology(res.F, len(res.V))
    ang = dihedral_angles(face_normals(res.V, res.F), topo)
    new = np.zeros(len(res.F), bool)
    new[res.new_faces] = True
    a, b = topo.edge_faces[:, 0], topo.edge_faces[:, 1]
    inner = b >= 0
    b = np.maximum(b, 0)
    seam = inner & (new[a] != new[b])
    near = np.zeros(len(res.V), bool)
    near[res.F[res.new_faces].ravel()] = True
    for _ in range(3):
        near[res.F[near[res.F].any(axis=1)].ravel()] = True
    ring = near[res.F].all(axis=1) & ~new
    sur = inner & ring[a] & ring[b]
    nan = float("nan")
    return (float(ang[seam].mean()) if seam.any() else nan,
            float(ang[sur].mean()) if sur.any() else nan)


def errors(res, V_gt, F_gt, diag):
    P = compact(res.V, res.F[res.new_faces])
    G = compact(V_gt, F_gt)
    d = distances(*P, *G)
    n, ng = face_normals(*P), face_normals(*G)
    _, i = cKDTree(G[0][G[1]].mean(axis=1)).query(P[0][P[1]].mean(axis=1))
    ang = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", n, ng[i]), -1, 1)))
    return d["mean"] / diag, d["hausdorff"] / diag, float(ang.mean())


def row(case, variant, res, err, dt):
    m, h, nd = err if err is not None else (float("nan"),) * 3
    status = f"{res.n_filled}/{len(res.holes)}"
    seam, ring = seam_angles(res)
    meth = ",".join(sorted({r.reason.split(",")[0] for r in res.holes if r.status == "filled"}))
    return (f"| {case:<30} | {variant:<10} | {m * 1e3:8.3f} | {h * 1e3:8.2f} | {nd:7.2f} | "
            f"{seam:6.2f} | {ring:6.2f} | {dt:5.2f} | {len(res.new_vertices):5d} | "
            f"{len(res.new_faces):5d} | {status:>6} | {meth:<6} |")


HEADER = (f"| {'case':<30} | variant    | mean e-3 | Haus e-3 | normal° |  seam° |  ring° |   t s |"
          " new V | new F | filled | method |\n"
          "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")


def run_cut_cases(lines):
    import trimesh

    V, F, _ = _common.read("spot")
    V, F = trimesh.remesh.subdivide_loop(V, F, iterations=1)
    V, F = np.asarray(V, float), np.asarray(F, np.int64)
    Vf, Ff, _ = _common.read("fandisk")
    cases = [("smooth", V, F, (0.47, 0.0, 0.2)),
             ("CAD smooth part", Vf, Ff, (1.21, 14.06, -1.61)),
             ("CAD creases", Vf, Ff, (3.19, 14.41, -2.39))]
    for name, V, F, p in cases:
        diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
        c = int(np.argmin(np.linalg.norm(V - np.asarray(p), axis=1)))
        for r in (4, 8, 16):
            Vc, Fc, F_gt = cut_disc(V, F, c, r)
            for var, kw in VARIANTS.items():
                t = time.perf_counter()
                res = fill_holes(Vc, Fc, **kw)
                dt = time.perf_counter() - t
                err = errors(res, V, F_gt, diag) if len(res.new_faces) else None
                lines.append(row(f"{name} r={r} ({len(F_gt)} F)", var, res, err, dt))
                print(lines[-1], flush=True)


def run_bunny(lines):
    V, F, _ = _common.read("bunny")
    for var, kw in VARIANTS.items():
        t = time.perf_counter()
        res = fill_holes(V, F, **kw)
        dt = time.perf_counter() - t
        lines.append(row("bunny 5 real holes", var, res, None, dt))
        print(lines[-1], flush=True)


def run_denoise(lines):
    import trimesh  # noqa: F401

    from meshrepair.model.noise import add_noise

    V, F, _ = _common.read("spot")
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    Vn = add_noise(V, F, 0.2, seed=1)
    c = int(np.argmin(np.linalg.norm(V - np.array([0.47, 0.0, 0.2]), axis=1)))
    inside = edge_graph_distances(V, F, c) < 4 * mean_edge_length(V, F)
    removed = inside[F].any(axis=1)
    Vc, Fc = compact(Vn, F[~removed])  # the noisy positions, cut where the clean mesh is
    used = np.unique(F[~removed])  # the kept vertices, in the order compact keeps them
    out = ["", "Fill + denoise (spot.ply, normal noise γ = 0.2, disc r = 4 cut from the noisy "
           "mesh): surround = mean distance of the kept vertices to their clean positions / "
           "diagonal; dihedral = mean over the patch border edges vs the surround within 3 rings",
           "", "| variant | surround e-3 | patch mean e-3 | patch Haus e-3 | border° | "
           "surround° | t s |", "|---|---:|---:|---:|---:|---:|---:|"]
    for var, kw in (("fill only", {}), ("fill + denoise", {"denoise": True})):
        t = time.perf_counter()
        res = fill_holes(Vc, Fc, **kw)
        dt = time.perf_counter() - t
        m, h, _ = errors(res, V, F[removed], diag)
        sur = np.linalg.norm(res.V[: len(Vc)] - V[used], axis=1).mean() / diag
        tp = edge_topology(res.F, len(res.V))
        ang = dihedral_angles(face_normals(res.V, res.F), tp)
        new = np.zeros(len(res.F), bool)
        new[res.new_faces] = True
        a, b = tp.edge_faces[:, 0], np.maximum(tp.edge_faces[:, 1], 0)
        near = np.zeros(len(res.V), bool)
        near[res.F[res.new_faces].ravel()] = True
        for _ in range(3):
            near[res.F[near[res.F].any(axis=1)].ravel()] = True
        ring = near[res.F].all(axis=1) & ~new
        out.append(f"| {var} | {sur * 1e3:.3f} | {m * 1e3:.3f} | {h * 1e3:.2f} | "
                   f"{ang[new[a] != new[b]].mean():.2f} | {ang[ring[a] & ring[b]].mean():.2f} | "
                   f"{dt:.2f} |")
    print("\n".join(out), flush=True)
    lines.extend(out)


def bunny_picture(path: str) -> None:
    """The picture at the top of docs/holes.md: bunny's real holes before and after."""
    from meshrepair.render import compare_figure

    V, F, _ = _common.read("bunny")
    res = fill_holes(V, F)
    region = np.zeros(len(res.F), bool)
    region[res.new_faces] = True
    compare_figure([(V, F), (res.V, res.F)], ["bunny (5 scan holes)", "fill_holes"],
                   metrics=["", f"{len(res.new_vertices)} new vertices, "
                                f"{len(res.new_faces)} new faces"],
                   out_path=path, width=500, height=500, elevation=-70.0, shading="smooth",
                   region_mask=[None, region])
    print(f"wrote {path}", flush=True)


def crease_picture(path: str, name: str = "fandisk", kind: str = "crease",
                   radius: int = 8) -> None:
    """docs/img/holes_crease.png: a hole cut across a crease of a CAD mesh, refilled by
    meshrepair (crease continued) and by CGAL refine-and-fair, next to the truth."""
    import _holes_peers

    from meshrepair.render import compare_figure

    V, F, _ = _common.read(name)
    c = [x for x in _holes_peers.pick_centres(V, F) if x[0] == kind][0][1]
    Vc, Fc, F_rm = cut_disc(V, F, c, radius)
    le = mean_edge_length(V, F)
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    outs = [("truth", V, F, None), ("cut", Vc, Fc, None)]
    for mname in ("meshrepair", "CGAL refine+fair"):
        fn = _holes_peers.PEERS[mname]
        try:
            Vo, Fo = fn(Vc, Fc, le)
        except Exception as exc:  # noqa: BLE001
            print(f"{mname} skipped: {exc!r}")
            continue
        new = _holes_peers.new_faces(Vc, Fc, Vo, Fo)
        m = _holes_peers.measure(V, F_rm, V, F, Vo, Fo, new, diag, le)
        outs.append((f"{mname}\nnormal {m[2]:.1f}°, crease {m[4]:.0f}° (truth {m[5]:.0f}°)",
                     Vo, Fo, new))
    centre = V[c]
    # view along the mean normal of the faces round the centre; crop to the neighbourhood
    fn_ = face_normals(V, F)
    near = np.linalg.norm(V[F].mean(axis=1) - centre, axis=1) < 3 * le
    n = fn_[near].sum(axis=0)
    n /= np.linalg.norm(n)
    az, el = np.degrees(np.arctan2(n[0], n[2])), np.degrees(np.arcsin(np.clip(n[1], -1, 1)))
    meshes, titles, regions = [], [], []
    for title, Vx, Fx, new in outs:
        keep = np.linalg.norm(Vx[Fx].mean(axis=1) - centre, axis=1) < 1.4 * radius * le
        reg = np.zeros(len(Fx), bool)
        if new is not None:
            reg[new] = True
        meshes.append((Vx, Fx[keep]))
        regions.append(reg[keep])
        titles.append(title)
    compare_figure(meshes, titles, out_path=path, width=420, height=420, azimuth=az,
                   elevation=el, fit="first", region_mask=regions, color_by="none",
                   shading="flat")
    print(f"wrote {path}", flush=True)


def main() -> None:
    import argparse

    import meshrepair.fill.options

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--enclose", default=None,
                    help="comma-separated order of enclosing methods (auto, liepa); default: "
                         f"{','.join(meshrepair.fill.options.ENCLOSE_ORDER)}")
    ap.add_argument("--cases", default="cut,bunny,denoise",
                    help="comma-separated subset of: cut, bunny, denoise, peers (cut-and-refill "
                         "against CGAL, MeshLib, pymeshfix), real (the shared meshes with real "
                         "holes at defaults: time and peak RSS)")
    ap.add_argument("--smooth", default="spot,nefertiti",
                    help="smooth meshes of the peers case (default: spot,nefertiti)")
    ap.add_argument("--cad", default="fandisk,twelve,trim_star,rocker_arm",
                    help="CAD meshes of the peers case (holes across a corner and a crease)")
    ap.add_argument("--meshes", default=None,
                    help="protocol case: comma-separated shared meshes (default: every shared "
                         "real mesh, CAD then organic)")
    ap.add_argument("--radii", default="4,8,16,24", help="protocol case: radii in l̄")
    ap.add_argument("--seeds", default="0,1,2", help="protocol case: seeds of the cut")
    ap.add_argument("--methods", default=None,
                    help="protocol case: comma-separated methods (default: all)")
    ap.add_argument("--jsonl", default=None,
                    help="protocol case: append one JSON record per run to this file")
    ap.add_argument("--from-jsonl", default=None,
                    help="protocol case: only print the table of the records in this file")
    ap.add_argument("--fitted", action="store_true",
                    help="meshrepair fills with fill_holes(fitted=True) (the fitted-surface "
                         "candidate, docs/holes.md section 5)")
    ap.add_argument("--option", action="append", default=[], metavar="KEY=VALUE",
                    help="a keyword of meshrepair's fill_holes in the protocol and peers cases "
                         "(repeatable), e.g. triharmonic=False")
    ap.add_argument("--picture", metavar="PNG", default=None,
                    help="only write the bunny before/after picture (docs/img/holes_bunny.png)")
    ap.add_argument("--crease-picture", metavar="PNG", default=None,
                    help="only write the crease-through-a-hole picture (docs/img/holes_crease.png)")
    args = ap.parse_args()
    if args.picture:
        bunny_picture(args.picture)
        return
    if args.crease_picture:
        crease_picture(args.crease_picture)
        return
    if args.enclose:
        order = tuple(m.strip() for m in args.enclose.split(","))
        if not order or set(order) - {"auto", "liepa"}:
            ap.error("--enclose takes methods among: auto, liepa")
        meshrepair.fill.options.ENCLOSE_ORDER = order
    if args.from_jsonl:
        import json

        import _holes_protocol

        recs = [json.loads(x) for x in open(args.from_jsonl) if x.strip()]
        print("\n".join(_holes_protocol.table(recs)))
        return
    cases = {c.strip() for c in args.cases.split(",")}
    if cases - {"cut", "bunny", "denoise", "peers", "real", "protocol"}:
        ap.error("--cases takes: cut, bunny, denoise, peers, real, protocol")
    _common.limit_threads(1)
    info = _common.machine_info()
    print(f"machine: {info.get('cpu', '?')}, {info.get('cores')} cores; python {info['python']}, "
          f"numpy {info['numpy']}, scipy {info.get('scipy')}; git {info.get('git')}")
    lines = [HEADER] if cases & {"cut", "bunny"} else []
    if lines:
        print(HEADER, flush=True)
    print(f"enclosing order: {','.join(meshrepair.fill.options.ENCLOSE_ORDER)}", flush=True)
    _common.warm_imports(jit=True)
    # compile (or load) the numba kernel of Liepa's triangulation outside the timings
    from meshrepair.holes import min_weight_triangulation

    t = np.linspace(0, 2 * np.pi, 9)[:-1]
    min_weight_triangulation(np.c_[np.cos(t), np.sin(t), np.cos(2 * t)])
    if "cut" in cases:
        run_cut_cases(lines)
    if "bunny" in cases:
        run_bunny(lines)
    if "denoise" in cases:
        run_denoise(lines)
    if "real" in cases or "peers" in cases:
        import _holes_peers

        if "real" in cases:
            lines.append("")
            _holes_peers.run_real(lines)
        if "peers" in cases:
            notes: list[str] = []
            smooth = {"spot": (0.47, 0.0, 0.2), "nefertiti": None}
            sm = []
            for nm in [x.strip() for x in args.smooth.split(",") if x.strip()]:
                if smooth.get(nm) is None:
                    Vx, Fx, _ = _common.read(nm)
                    smooth[nm] = tuple(Vx[len(Vx) // 3])  # a deterministic vertex
                sm.append((nm, smooth[nm]))
            lines.append("")
            _holes_peers.run_peers(cut_disc, lines, notes, sm,
                                   [x.strip() for x in args.cad.split(",") if x.strip()])
            lines.extend(notes)
    if args.fitted or args.option:
        import _holes_peers

        if args.fitted:
            _holes_peers.MESHREPAIR_OPTIONS["fitted"] = True
        _holes_peers.MESHREPAIR_OPTIONS.update(_common.keyword_option(o) for o in args.option)
        print(f"meshrepair fill_holes options: {_holes_peers.MESHREPAIR_OPTIONS}", flush=True)
    if "protocol" in cases:
        import _holes_protocol

        notes = []
        meshes = ([x.strip() for x in args.meshes.split(",") if x.strip()] if args.meshes
                  else list(_holes_protocol.CAD + _holes_protocol.ORGANIC))
        _holes_protocol.run_protocol(
            lines, notes, meshes, [float(x) for x in args.radii.split(",")],
            [int(x) for x in args.seeds.split(",")], out_jsonl=args.jsonl,
            methods=args.methods.split(",") if args.methods else None)
        lines.extend(notes)
    print("\n--- table ---")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
