"""meshrepair's defaults against research methods' own published outputs (issue 12).

Every triple ``<case>__truth.ply``, ``<case>__noisy.ply``, ``<case>__published.ply`` in
``../shared/meshes/published/`` (see its MANIFEST.md): meshrepair's ``denoise(V, F)`` with its
defaults on the noisy input, beside the output the method's authors published on the same input.

Columns: MSAE (33) in deg² and E_a (mean face-normal angle, degrees) of the published output and of
meshrepair, their ratios (meshrepair / published; ≤ 1 means meshrepair is at least as good), E_V
(34) of both (MSAE bought by over-smoothing, with a worse E_V, is not a win), and the wall time of
the ``denoise`` call (median of ``--repeats``). The machine's memory probe is printed with the
table (benchmarks/_common.py).

Usage::

    python benchmarks/published.py                 # all 7 triples
    python benchmarks/published.py --only kinect   # a subset (regex on the case name)
    python benchmarks/published.py --out table.md --json rows.json
    python benchmarks/published.py --picture docs/img   # noisy | meshrepair | published | truth
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402, I001  (sets the thread env vars before numpy is imported)
import numpy as np  # noqa: E402

PUBLISHED = C.MESHES / "published"


def cases() -> list[str]:
    """Case names ``<case>`` with all three files present, sorted."""
    names = sorted(p.name[: -len("__truth.ply")] for p in PUBLISHED.glob("*__truth.ply"))
    out = []
    for n in names:
        if all((PUBLISHED / f"{n}__{k}.ply").exists() for k in ("noisy", "published")):
            out.append(n)
    if not out:
        raise SystemExit(f"no published triples under {PUBLISHED}: set MESHREPAIR_SHARED_MESHES")
    return out


def mean_angle(V, V_ref, F) -> float:
    """E_a: mean angle (degrees) between corresponding face normals."""
    from meshrepair.metrics import mean_angle_error

    return mean_angle_error(V, V_ref, F)


def run(name: str, repeats: int = 1, kwargs: dict | None = None) -> dict:
    from meshrepair import denoise, msae, read_mesh, vertex_error

    t = read_mesh(PUBLISHED / f"{name}__truth.ply")
    n = read_mesh(PUBLISHED / f"{name}__noisy.ply")
    p = read_mesh(PUBLISHED / f"{name}__published.ply")
    F = t.F
    if not (np.array_equal(F, n.F) and np.array_equal(F, p.F)):
        raise SystemExit(f"{name}: the three files do not share faces")
    times = []
    res = None
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        res = denoise(n.V, F, **(kwargs or {}))
        times.append(time.perf_counter() - t0)
    row = {"case": name, "nV": len(t.V), "time_s": float(np.median(times)),
           "iterations": res.iterations, "noise_estimate": res.noise_estimate,
           "params": {k: v for k, v in res.params.items() if isinstance(v, (int, float, str))}}
    for tag, V in (("noisy", n.V), ("published", p.V), ("ours", res.V)):
        row[f"msae_{tag}"] = msae(V, t.V, F)
        row[f"ea_{tag}"] = mean_angle(V, t.V, F)
        row[f"ev_{tag}"] = vertex_error(V, t.V)
    row["msae_ratio"] = row["msae_ours"] / row["msae_published"]
    row["ea_ratio"] = row["ea_ours"] / row["ea_published"]
    row["ev_ratio"] = row["ev_ours"] / row["ev_published"]
    return row


PICTURES = {  # case -> (file stem, camera azimuth, elevation)
    "nllr_nicolo": ("published_organic_nicolo", 0.0, 0.0),
    "nllr_igea": ("published_organic_igea", 0.0, 0.0),
    "tgv_kinect_pyramid": ("published_scan_kinect", 0.0, 0.0),
}


def picture(name: str, folder: Path, size: int = 420) -> Path:
    """noisy | meshrepair | published | truth for one triple, MSAE / E_a under each panel."""
    from meshrepair import denoise, msae, read_mesh
    from meshrepair.render import compare_figure

    t = read_mesh(PUBLISHED / f"{name}__truth.ply")
    n = read_mesh(PUBLISHED / f"{name}__noisy.ply")
    p = read_mesh(PUBLISHED / f"{name}__published.ply")
    r = denoise(n.V, t.F)
    stem, az, el = PICTURES.get(name, (f"published_{name}", 0.0, 0.0))
    Vs = [n.V, r.V, p.V, t.V]
    metrics = [f"MSAE {msae(V, t.V, t.F):.1f}, E_a {mean_angle(V, t.V, t.F):.2f}°" for V in Vs]
    method = {"tgv": "MeshTGV", "gcn": "GCN-Denoiser", "nllr": "NLLR"}[name.split("_")[0]]
    out = folder / f"{stem}.png"
    compare_figure([(V, t.F) for V in Vs], ["noisy", "meshrepair (defaults)",
                                             f"published ({method})", "truth"],
                   metrics=metrics, out_path=out, width=size, height=size, azimuth=az,
                   elevation=el)
    return out


def markdown(rows: list[dict]) -> str:
    out = ["| case | nV | noisy MSAE / E_a | published MSAE / E_a | meshrepair MSAE / E_a | "
           "MSAE ratio | E_a ratio | E_V noisy | E_V published | E_V meshrepair | E_V ratio | "
           "time s |",
           "|---|---:|---|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        out.append(
            f"| {r['case']} | {r['nV']:,} | {r['msae_noisy']:.1f} / {r['ea_noisy']:.2f}° | "
            f"{r['msae_published']:.2f} / {r['ea_published']:.2f}° | "
            f"{r['msae_ours']:.2f} / {r['ea_ours']:.2f}° | {r['msae_ratio']:.2f} | "
            f"{r['ea_ratio']:.2f} | {r['ev_noisy']:.3e} | {r['ev_published']:.3e} | "
            f"{r['ev_ours']:.3e} | {r['ev_ratio']:.2f} | {r['time_s']:.2f} |")
    win = sum(r["msae_ratio"] <= 1 and r["ea_ratio"] <= 1 for r in rows)
    out.append("")
    out.append(f"ratio ≤ 1 on both MSAE and E_a: {win} of {len(rows)}; "
               f"E_V not worse than published: "
               f"{sum(r['ev_ratio'] <= 1 for r in rows)} of {len(rows)}")
    return "\n".join(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", help="regex on the case name")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--kwargs", default="{}", help="JSON dict passed to denoise (default: none)")
    ap.add_argument("--out", help="write the markdown table here")
    ap.add_argument("--json", help="write the rows as JSON here")
    ap.add_argument("--picture", metavar="DIR",
                    help="also render noisy | meshrepair | published | truth PNGs into DIR")
    args = ap.parse_args(argv)
    C.limit_threads(1)
    info = C.machine_info()
    C.warm_imports()
    names = cases()
    if args.only:
        names = [n for n in names if re.search(args.only, n, re.I)]
    rows = []
    for n in names:
        r = run(n, args.repeats, json.loads(args.kwargs))
        rows.append(r)
        print(f"{n}: MSAE {r['msae_ours']:.2f} vs {r['msae_published']:.2f} "
              f"(ratio {r['msae_ratio']:.2f}), E_a ratio {r['ea_ratio']:.2f}, "
              f"E_V ratio {r['ev_ratio']:.2f}, {r['time_s']:.2f} s", flush=True)
    md = (f"machine: {info.get('cpu')}, {info.get('cores')} cores, load {info.get('loadavg')}, "
          f"memory probe {info['memprobe_ms']} ms, git {info['git']}\n\n" + markdown(rows))
    print()
    print(md)
    if args.out:
        C.write_text(args.out, md + "\n")
    if args.json:
        C.write_text(args.json, json.dumps({"machine": info, "rows": rows}, indent=1))
    if args.picture:
        for n in names:
            if n in PICTURES:
                print("wrote", picture(n, Path(args.picture)))


if __name__ == "__main__":
    main()
