"""The same surface at another resolution must get the same treatment (issue 12).

For shared truths (organic: spot, bunny, nicolo, rocker_arm, camelhead; CAD: fandisk, twelve,
sharp_sphere, trim_star, screwdriver) the script builds versions at other resolutions

* ``dec``: quadric-edge-collapse decimation to 1/4 of the faces (PyMeshLab, from ``.[bench]``),
  kept only when the result is still an edge-manifold closed-or-bordered mesh of one component;
* ``x1``: the shared mesh itself;
* ``sub1`` / ``sub2``: subdivided once / twice, Loop subdivision on the organic meshes (a smooth
  limit surface) and midpoint subdivision on the CAD parts (the creases stay exact);
  ``mid3``: midpoint subdivision three times (spot, 187k vertices: the failure of
  docs/parameters.md's weakest points, in ``--big``),

adds noise (32) (``meshrepair.add_noise``, σ = γ × the *new* mean edge length, seed 0) at γ 0.1 /
0.3 / 0.5, along the normals and in random directions, and prints one row per input: the branch
the defaults take (``class``: organic or CAD, i.e. whether the outside weight
fired; the crease-supported fraction; the noise read γ̂; impulsive; the discrepancy re-solve;
the coarse-to-fine low-pass of the input), MSAE / E_V against the (re-sampled) truth, the time of
``denoise``, and the in-house Taubin at its defaults (:func:`meshrepair.baselines.taubin_smooth`)
as a floor. A row is *flipped* when its class differs from the same mesh and noise at ``x1``.

    python benchmarks/resolution.py                 # default grid, ~10 min on 2 cores
    python benchmarks/resolution.py --quick         # a few rows
    python benchmarks/resolution.py --big           # every noise, sub2 of every mesh, spot mid3
    python benchmarks/resolution.py --json out.json
    python benchmarks/resolution.py --table before.json after.json

Inputs are cached as ``.npz`` in ``MESHREPAIR_BENCH_CACHE`` so two trees run on identical data.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402, I001  (sets the thread env vars before numpy is imported)
import numpy as np  # noqa: E402

ORGANIC = ("spot", "bunny", "nicolo", "rocker_arm", "camelhead")
CAD = ("fandisk", "twelve", "sharp_sphere", "trim_star", "screwdriver")
NOISES = ((0.1, "normal"), (0.3, "normal"), (0.5, "normal"), (0.1, "random"), (0.3, "random"),
          (0.5, "random"))
# the default grid: every mesh at dec / x1 / sub1 at γ0.3 and γ0.5 normal, γ0.5 random; the
# larger meshes (bunny, nicolo) skip sub1 unless --big (their sub1 is 140k / 60k vertices)
DEFAULT_NOISES = ((0.3, "normal"), (0.5, "normal"), (0.5, "random"))
QUICK = [("spot", "sub2", 0.5, "normal"), ("spot", "x1", 0.5, "normal"),
         ("fandisk", "sub2", 0.3, "normal"), ("fandisk", "x1", 0.3, "normal"),
         ("nicolo", "dec", 0.3, "normal")]
BIG_SKIP_SUB1 = ("bunny",)


def _manifold_single(V, F) -> bool:
    from meshrepair.mesh.topology import edge_topology

    try:
        topo = edge_topology(F, len(V))
    except Exception:  # non-manifold edges
        return False
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    e = topo.edges
    A = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(len(V), len(V)))
    used = np.zeros(len(V), bool)
    used[F.ravel()] = True
    return bool(used.all() and connected_components(A, directed=False)[0] == 1)


def _resample(name: str, level: str):
    """Truth ``(V, F)`` of ``name`` at ``level`` (None when the level cannot be built)."""
    import trimesh
    import trimesh.remesh

    V, F, _ = C.read(name)
    if level == "x1":
        return V, F
    if level.startswith(("sub", "mid")):
        for _ in range(int(level[3:])):
            if name in ORGANIC and level.startswith("sub"):
                V, F = trimesh.remesh.subdivide_loop(V, F, iterations=1)
            else:
                V, F = trimesh.remesh.subdivide(V, F)
        return np.ascontiguousarray(V, np.float64), np.ascontiguousarray(F, np.int64)
    if level == "dec":
        import pymeshlab

        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(V, F))
        ms.meshing_decimation_quadric_edge_collapse(targetfacenum=len(F) // 4,
                                                    preservetopology=True, preserveboundary=True,
                                                    planarquadric=True)
        ms.meshing_remove_unreferenced_vertices()
        m = ms.current_mesh()
        Vd = np.ascontiguousarray(m.vertex_matrix(), np.float64)
        Fd = np.ascontiguousarray(m.face_matrix(), np.int64)
        return (Vd, Fd) if _manifold_single(Vd, Fd) else None
    raise ValueError(level)


def case_inputs(name: str, level: str, gamma: float, direction: str):
    """``(V_truth, V_noisy, F)`` cached as npz (None when the level cannot be built)."""
    from meshrepair import add_noise

    C.CACHE.mkdir(parents=True, exist_ok=True)
    p = C.CACHE / f"res_{name}_{level}_g{gamma}_{direction}_s0.npz"
    if p.exists():
        z = np.load(p)
        if "none" in z.files:
            return None
        return z["V"], z["Vn"], z["F"]
    tf = C.CACHE / f"res_{name}_{level}_truth.npz"
    if tf.exists():
        z = np.load(tf)
        tr = None if "none" in z.files else (z["V"], z["F"])
    else:
        tr = _resample(name, level)
        if tr is None:
            np.savez(tf, none=np.zeros(1))
        else:
            np.savez(tf, V=tr[0], F=tr[1])
    if tr is None:
        np.savez(p, none=np.zeros(1))
        return None
    V, F = tr
    Vn = add_noise(V, F, gamma, direction=direction, seed=0)
    np.savez(p, V=V, Vn=Vn, F=F)
    return V, Vn, F


def run_row(name, level, gamma, direction) -> dict | None:
    from meshrepair import denoise, msae, vertex_error
    from meshrepair.baselines import taubin_smooth

    inp = case_inputs(name, level, gamma, direction)
    if inp is None:
        return None
    V, Vn, F = inp
    t = time.process_time()
    r = denoise(Vn, F)
    dt = time.process_time() - t
    p = r.params
    Vt = taubin_smooth(Vn, F)
    return {"mesh": name, "kind": "organic" if name in ORGANIC else "CAD", "level": level,
            "gamma": gamma, "direction": direction, "n_vertices": int(len(V)),
            "cls": "CAD" if p.get("outside_weight", 1.0) != 1.0 else "organic",
            "support": float(p.get("presmooth_support_fraction",
                                   p.get("support_fraction", float("nan")))),
            "noise_read": float(r.noise_estimate), "impulsive": bool(p.get("impulsive")),
            "resolve": bool(p.get("outside_weight", 1.0) not in (6.0, 1.0)),
            "outside_weight": float(p.get("outside_weight", 1.0)),
            "presmooth": int(p.get("presmooth_steps", 0)),
            "msae": float(msae(r.V, V, F)), "ev": float(vertex_error(r.V, V)),
            "time": dt, "taubin_msae": float(msae(Vt, V, F)),
            "taubin_ev": float(vertex_error(Vt, V)),
            "noisy_msae": float(msae(Vn, V, F))}


def grid(quick: bool, big: bool) -> list[tuple]:
    if quick:
        return list(QUICK)
    rows = []
    for name in ORGANIC + CAD:
        levels = ["dec", "x1"]
        if name not in BIG_SKIP_SUB1 or big:
            levels.append("sub1")
        if big:
            levels.append("sub2")
        for lv in levels:
            for g, d in (NOISES if big else DEFAULT_NOISES):
                rows.append((name, lv, g, d))
    if not big:  # one finer row of each kind: 47k vertices (q 60), 104k vertices (q 76)
        rows += [("spot", "sub2", 0.5, "normal"), ("fandisk", "sub2", 0.3, "normal")]
    else:
        rows.append(("spot", "mid3", 0.5, "normal"))  # the known failure (187k vertices)
    return rows


def table(rows: list[dict], before: list[dict] | None = None) -> str:
    ref = {(r["mesh"], r["gamma"], r["direction"]): r["cls"] for r in rows if r["level"] == "x1"}
    old = {(r["mesh"], r["level"], r["gamma"], r["direction"]): r for r in (before or [])}
    head = ("| mesh | kind | level | nV | noise | class | support | γ̂ | imp. | re-solve | "
            "presmooth | MSAE | E_V | time (s) | Taubin MSAE / E_V | flipped |")
    if before is not None:
        head += " before: class / MSAE / E_V / time |"
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for r in rows:
        key = (r["mesh"], r["gamma"], r["direction"])
        flip = "**yes**" if key in ref and ref[key] != r["cls"] else ""
        s = (f"| {r['mesh']} | {r['kind']} | {r['level']} | {r['n_vertices']:,} | "
             f"γ{r['gamma']} {r['direction']} | {r['cls']} | {100 * r['support']:.1f} % | "
             f"{r['noise_read']:.3f} | {'yes' if r['impulsive'] else ''} | "
             f"{'yes' if r['resolve'] else ''} | {r['presmooth'] or ''} | {r['msae']:.2f} | "
             f"{r['ev']:.3g} | {r['time']:.1f} | {r['taubin_msae']:.2f} / {r['taubin_ev']:.3g} | "
             f"{flip} |")
        if before is not None:
            b = old.get((r["mesh"], r["level"], r["gamma"], r["direction"]))
            s += (f" {b['cls']} / {b['msae']:.2f} / {b['ev']:.3g} / {b['time']:.1f} |"
                  if b else " |")
        lines.append(s)
    return "\n".join(lines)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="a few rows only")
    ap.add_argument("--big", action="store_true", help="every noise and sub2 of every mesh")
    ap.add_argument("--only", help="rows whose 'mesh level' contains this text")
    ap.add_argument("--json", help="write the rows to this file")
    ap.add_argument("--table", nargs=2, metavar=("BEFORE", "AFTER"),
                    help="print the table of AFTER with BEFORE's figures beside it")
    a = ap.parse_args(argv)
    if a.table:
        before, after = (json.loads(Path(x).read_text()) for x in a.table)
        print(table(after, before))
        return
    C.limit_threads(1)
    C.warm_imports()
    rows = []
    for name, lv, g, d in grid(a.quick, a.big):
        if a.only and a.only not in f"{name} {lv}":
            continue
        r = run_row(name, lv, g, d)
        if r is None:
            print(f"# {name} {lv}: not built (decimation not manifold)", file=sys.stderr)
            continue
        rows.append(r)
        print(f"# {name} {lv} γ{g} {d}: {r['cls']} support {r['support']:.3f} "
              f"MSAE {r['msae']:.2f} ({r['time']:.1f} s)", file=sys.stderr, flush=True)
    if a.json:
        C.write_text(a.json, json.dumps(rows, indent=1))
    print(table(rows))
    n_flip = sum(1 for line in table(rows).splitlines() if "**yes**" in line)
    print(f"\n{len(rows)} rows, {n_flip} with a class other than the same mesh and noise at x1")


if __name__ == "__main__":
    main()
