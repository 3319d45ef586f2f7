"""Cut-and-refill against peer hole fillers (issue 13), and the real-hole cost table.

Used by ``benchmarks/holes.py --cases peers,real``. Peers (each optional; a missing one is
reported, never faked):

* CGAL ``Polygon_mesh_processing::triangulate_refine_and_fair_hole`` (PyPI ``cgal`` SWIG bindings;
  Liepa triangulation, refinement, fairing), every hole;
* MeshLib ``fillHoleNicely`` (subdivide to the mean edge length, ``smoothCurvature=True``);
* pymeshfix (MeshFix ``PyTMesh.fill_small_boundaries(refine=True)``, every boundary).

Metrics of the patch (the faces a method added) against the removed faces: symmetric mean and
Hausdorff distance / bounding-box diagonal; mean angle between every patch face normal and the
normal of the nearest removed face; for CAD holes the *crease error*: for every sharp edge of the
truth inside the hole (dihedral angle > 30°), the largest dihedral angle of the output edges
within one mean edge length of its midpoint, compared with the truth's angle (mean |difference|).
Time: wall seconds of the fill; memory: resident high-water mark of the fill above the RSS
before it (``/proc/self/clear_refs``), MiB.
"""

from __future__ import annotations

import os
import tempfile
import time

import _common
import numpy as np
from scipy.spatial import cKDTree

from meshrepair.mesh.geometry import dihedral_angles, face_normals, mean_edge_length
from meshrepair.mesh.topology import edge_topology
from meshrepair.metrics import distances

# ------------------------------------------------------------------------------------------------
# peers
# ------------------------------------------------------------------------------------------------


MESHREPAIR_OPTIONS: dict = {}
"""Keyword options of meshrepair's ``fill_holes`` in the benchmarks (``holes.py --fitted``,
``--option KEY=VALUE``)."""

LAST_NOTES: list[str] = []
"""The skipped loops and the notes of meshrepair's last fill (index, edges, status, reason,
note), for the protocol's records."""


def _meshrepair(V, F, hc):
    from meshrepair.fill import fill_holes

    r = fill_holes(V, F, **MESHREPAIR_OPTIONS)
    LAST_NOTES[:] = [f"{h.index} ({h.n_boundary} edges) {h.status}: {h.reason}; {h.note}"
                     for h in r.holes if h.status != "filled" or h.note
                     or h.reason.startswith("split")]
    return r.V, r.F


def _cgal(V, F, hc):
    from CGAL import CGAL_Polygon_mesh_processing as PMP
    from CGAL.CGAL_Polyhedron_3 import Polyhedron_3

    d = tempfile.mkdtemp()
    p = os.path.join(d, "in.off")
    with open(p, "w") as fh:
        fh.write(f"OFF\n{len(V)} {len(F)} 0\n")
        np.savetxt(fh, V, fmt="%.17g")
        np.savetxt(fh, np.c_[np.full(len(F), 3), F], fmt="%d")
    P = Polyhedron_3(p)
    seen, starts = set(), []
    for h in P.halfedges():
        if h.is_border() and h not in seen:
            starts.append(h)
            c = h
            while True:
                seen.add(c)
                c = c.next()
                if c == h:
                    break
    for h in starts:
        PMP.triangulate_refine_and_fair_hole(P, h, [], [])
    os.remove(p)
    os.rmdir(d)
    # read back through the handles (the OFF writer rounds to 5 significant digits)
    index: dict[tuple, int] = {}
    Vo = []
    for v in P.vertices():
        q = v.point()
        key = (q.x(), q.y(), q.z())
        index[key] = len(Vo)
        Vo.append(key)
    Fo = []
    for f in P.facets():
        h = f.halfedge()
        tri = []
        for _ in range(3):
            q = h.vertex().point()
            tri.append(index[(q.x(), q.y(), q.z())])
            h = h.next()
        Fo.append(tri)
    return np.asarray(Vo, float), np.asarray(Fo, np.int64)


def _meshlib(V, F, hc):
    import meshlib.mrmeshnumpy as mn
    import meshlib.mrmeshpy as mm

    m = mn.meshFromFacesVerts(np.ascontiguousarray(F, np.int32), np.ascontiguousarray(V))
    for e in list(m.topology.findHoleRepresentiveEdges()):
        s = mm.FillHoleNicelySettings()
        s.subdivideSettings.maxEdgeLen = hc
        s.smoothCurvature = True
        mm.fillHoleNicely(m, e, s)
    m.pack()
    return (np.asarray(mn.getNumpyVerts(m), float),
            np.asarray(mn.getNumpyFaces(m.topology), np.int64))


def _pymeshfix(V, F, hc):
    import pymeshfix

    t = pymeshfix.PyTMesh()
    t.set_quiet(True)
    t.load_array(np.ascontiguousarray(V, float), np.ascontiguousarray(F, np.int32))
    t.fill_small_boundaries(nbe=0, refine=True)
    Vo, Fo = t.return_arrays()
    return np.asarray(Vo, float), np.asarray(Fo, np.int64)


PEERS = {"meshrepair": _meshrepair, "CGAL refine+fair": _cgal,
         "MeshLib fillHoleNicely": _meshlib, "pymeshfix": _pymeshfix}


def available(notes: list[str]) -> dict:
    out = {"meshrepair": _meshrepair}
    for name, mod in (("CGAL refine+fair", "CGAL.CGAL_Polygon_mesh_processing"),
                      ("MeshLib fillHoleNicely", "meshlib.mrmeshpy"),
                      ("pymeshfix", "pymeshfix")):
        try:
            __import__(mod)
            out[name] = PEERS[name]
        except Exception as exc:  # noqa: BLE001
            notes.append(f"{name} skipped: cannot import {mod} ({exc!r})")
    return out


# ------------------------------------------------------------------------------------------------
# cutting and measuring
# ------------------------------------------------------------------------------------------------


def new_faces(V_in, F_in, V_out, F_out) -> np.ndarray:
    """Faces of the output that are not faces of the input (matched by vertex position)."""
    d, idx = cKDTree(V_in).query(V_out)
    diag = float(np.linalg.norm(np.ptp(V_in, axis=0)))
    same = d <= 1e-5 * diag  # MeshLib stores float32, CGAL's OFF writer rounds
    m = np.where(same, idx, -1)
    Fo = m[F_out]
    known = (Fo >= 0).all(axis=1)
    s_in = np.sort(F_in, axis=1)
    n = np.int64(len(V_in))
    codes_in = np.sort((s_in[:, 0] * n + s_in[:, 1]) * n + s_in[:, 2])
    so = np.sort(np.where(Fo >= 0, Fo, 0), axis=1)
    codes = (so[:, 0] * n + so[:, 1]) * n + so[:, 2]
    pos = np.clip(np.searchsorted(codes_in, codes), 0, len(codes_in) - 1)
    old = known & (codes_in[pos] == codes)
    return np.flatnonzero(~old)


def _compact(V, F):
    u = np.unique(F.ravel())
    m = -np.ones(len(V), np.int64)
    m[u] = np.arange(len(u))
    return V[u], m[F]


def measure(V_gt, F_gt_removed, V_gt_all, F_gt_all, V_out, F_out, new, diag, le):
    """Patch metrics: (mean/diag, haus/diag, normal deviation °, crease error °, restored °,
    truth °)."""
    if len(new) == 0:
        nan = float("nan")
        return nan, nan, nan, nan, nan, nan
    P = _compact(V_out, F_out[new])
    G = _compact(V_gt_all, F_gt_removed)
    d = distances(*P, *G)
    n, ng = face_normals(*P), face_normals(*G)
    _, i = cKDTree(G[0][G[1]].mean(axis=1)).query(P[0][P[1]].mean(axis=1))
    nd = float(np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", n, ng[i]), -1, 1))).mean())
    # crease error: truth sharp edges with both faces removed
    topo = edge_topology(F_gt_all, len(V_gt_all))
    ang = dihedral_angles(face_normals(V_gt_all, F_gt_all), topo)
    removed = np.zeros(len(F_gt_all), bool)
    fc = {tuple(sorted(f)) for f in F_gt_removed.tolist()}
    for fi, f in enumerate(F_gt_all.tolist()):
        if tuple(sorted(f)) in fc:
            removed[fi] = True
    ef = topo.edge_faces
    inner = (ef[:, 1] >= 0) & removed[ef[:, 0]] & removed[np.maximum(ef[:, 1], 0)]
    sharp = np.flatnonzero(inner & (ang > 30.0))
    if len(sharp) == 0:
        return d["mean"] / diag, d["hausdorff"] / diag, nd, float("nan"), float("nan"), \
            float("nan")
    tmid = V_gt_all[topo.edges[sharp]].mean(axis=1)
    to = edge_topology(F_out, len(V_out))
    ao = dihedral_angles(face_normals(V_out, F_out), to)
    newf = np.zeros(len(F_out), bool)
    newf[new] = True
    oe = np.flatnonzero(newf[to.edge_faces[:, 0]]
                        | (newf[np.maximum(to.edge_faces[:, 1], 0)] & (to.edge_faces[:, 1] >= 0)))
    omid = V_out[to.edges[oe]].mean(axis=1)
    tree = cKDTree(omid)
    near = tree.query_ball_point(tmid, r=le)
    rest = np.array([ao[oe[nb]].max() if nb else 0.0 for nb in near])
    err = float(np.abs(rest - ang[sharp]).mean())
    return (d["mean"] / diag, d["hausdorff"] / diag, nd, err, float(rest.mean()),
            float(ang[sharp].mean()))


def pick_centres(V, F, n_corner=1, n_crease=1):
    """A corner (vertex with >= 3 sharp edges) and a crease vertex (2 sharp edges, farthest from
    corners) of a CAD mesh, deterministic."""
    topo = edge_topology(F, len(V))
    ang = dihedral_angles(face_normals(V, F), topo)
    se = topo.edges[ang > 30.0]
    cnt = np.bincount(se.ravel(), minlength=len(V))
    corners = np.flatnonzero(cnt >= 3)
    crease = np.flatnonzero(cnt == 2)
    out = []
    if len(corners):
        # the corner whose nearest other corner is farthest (an isolated, well-formed corner)
        if len(corners) > 1:
            dd, _ = cKDTree(V[corners]).query(V[corners], k=2)
            out.append(("corner", int(corners[np.argmax(dd[:, 1])])))
        else:
            out.append(("corner", int(corners[0])))
    if len(crease) and len(corners):
        dd, _ = cKDTree(V[corners]).query(V[crease])
        out.append(("crease", int(crease[np.argmax(dd)])))
    elif len(crease):
        out.append(("crease", int(crease[len(crease) // 2])))
    return out


def run_peers(cut_disc, lines: list[str], notes: list[str], smooth_meshes, cad_meshes,
              smooth_radii=(4, 8, 16), cad_radii=(4, 8)) -> None:
    import trimesh

    methods = available(notes)
    head = ("| case | method | mean e-3 | Haus e-3 | normal° | crease err° | crease° (truth) | "
            "t s | peak MB | filled |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---|")
    lines.append(head)
    print(head, flush=True)
    cases = []
    for name, centre in smooth_meshes:
        V, F, _ = _common.read(name)
        if name == "spot":
            V, F = trimesh.remesh.subdivide_loop(V, F, iterations=1)
            V, F = np.asarray(V, float), np.asarray(F, np.int64)
        c = int(np.argmin(np.linalg.norm(V - np.asarray(centre), axis=1)))
        for r in smooth_radii:
            cases.append((f"{name} smooth r={r}", V, F, c, r))
    for name in cad_meshes:
        V, F, _ = _common.read(name)
        for kind, c in pick_centres(V, F):
            for r in cad_radii:
                cases.append((f"{name} {kind} r={r}", V, F, c, r))
    for label, V, F, c, r in cases:
        diag = float(np.linalg.norm(np.ptp(V, axis=0)))
        le = mean_edge_length(V, F)
        Vc, Fc, F_rm = cut_disc(V, F, c, r)
        # cut_disc compacts the vertices; map the removed faces' positions through V
        for mname, fn in methods.items():
            _common.reset_peak_rss()
            base = _common.rss_now_mb()
            t = time.perf_counter()
            try:
                Vo, Fo = fn(Vc, Fc, le)
                err = None
            except Exception as exc:  # noqa: BLE001
                err = repr(exc)[:60]
            dt = time.perf_counter() - t
            peak = _common.peak_rss_mb() - base
            if err is not None:
                row = f"| {label} | {mname} | failed: {err} | | | | | {dt:.2f} | {peak:.0f} | no |"
            else:
                new = new_faces(Vc, Fc, Vo, Fo)
                m, h, nd, ce, cr, ct = measure(V, F_rm, V, F, Vo, Fo, new, diag, le)
                bl = len(edge_topology(Fo, len(Vo)).edges[edge_topology(Fo, len(Vo)).boundary])
                filled = "yes" if bl == 0 else f"{bl} border edges left"
                crs = "" if np.isnan(ce) else f"{ce:.1f}"
                crt = "" if np.isnan(cr) else f"{cr:.1f} ({ct:.1f})"
                row = (f"| {label} | {mname} | {m * 1e3:.3f} | {h * 1e3:.2f} | {nd:.2f} | {crs} | "
                       f"{crt} | {dt:.2f} | {peak:.0f} | {filled} |")
            lines.append(row)
            print(row, flush=True)


def run_real(lines: list[str]) -> None:
    """Every shared mesh with real holes filled at defaults: time and peak RSS."""
    from meshrepair.fill import fill_holes

    head = ("| mesh | loops | filled | skipped (why) | new F | t s | peak MB (above RSS before) |"
            " peak RSS MB |\n|---|---:|---:|---|---:|---:|---:|---:|")
    lines.append(head)
    print(head, flush=True)
    for name in ("bunny", "kinect_pyramid", "camelhead", "nicolo", "scans/rabbit_scan"):
        V, F, _ = _common.read(name)
        _common.reset_peak_rss()
        base = _common.rss_now_mb()
        t = time.perf_counter()
        res = fill_holes(V, F)
        dt = time.perf_counter() - t
        peak = _common.peak_rss_mb()
        why = "; ".join(f"{h.index}: {h.reason.split('(')[0].strip()}" for h in res.holes
                        if h.status != "filled")
        row = (f"| {name} | {len(res.holes)} | {res.n_filled} | {why or '-'} | "
               f"{len(res.new_faces)} | {dt:.2f} | {peak - base:.0f} | {peak:.0f} |")
        lines.append(row)
        print(row, flush=True)
