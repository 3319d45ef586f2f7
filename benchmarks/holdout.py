"""Design set vs held-out set for the denoising defaults (issue 12; table in docs/parameters.md).

Runs ``denoise(V, F)`` at its defaults on the shared noisy/truth pairs, on synthetic noise (32)
(seed 7, the ablation's protocol) and on synthetic *correlated* noise (``meshrepair.denoise.scale
.correlated_noise``, m diffusion steps, seed 7), and prints MSAE, E_a, E_V and time per case,
with the set each case belongs to: the rules were chosen on the design set only.

    python benchmarks/holdout.py --json now.json
    PYTHONPATH=/path/to/old/src python benchmarks/holdout.py --json before.json   # other code
    python benchmarks/holdout.py --table before.json now.json                     # markdown

The correlated inputs are generated once with the code that has ``correlated_noise`` and cached
as ``.npy`` (``MESHREPAIR_BENCH_CACHE``), so older code is run on the very same inputs.
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

DESIGN = {"fandisk γ0.3 (published)", "fandisk γ0.7 (published)", "twelve impulsive 0.5",
          "sharp_sphere γ0.3", "nicolo γ0.2", "kinect_pyramid (real)", "fandisk γ0.4 normal",
          "fandisk γ0.4 random", "spot γ0.4 random"}
CASES = [
    ("pair", "fandisk γ0.3 (published)", "noisy/fandisk__gauss0.3", "fandisk"),
    ("pair", "fandisk γ0.7 (published)", "noisy/fandisk__gauss0.7", "fandisk"),
    ("pair", "twelve impulsive 0.5", "noisy/twelve__impulsive0.5", "twelve"),
    ("pair", "sharp_sphere γ0.3", "noisy/sharp_sphere__gauss0.3", "sharp_sphere"),
    ("pair", "trim_star n3", "noisy/trim_star__gauss_n3", "trim_star"),
    ("pair", "bunny γ0.2", "noisy/bunny__gauss0.2", "bunny"),
    ("pair", "nicolo γ0.2", "noisy/nicolo__gauss0.2", "nicolo"),
    ("pair", "kinect_pyramid (real)", "noisy/kinect_pyramid__kinect_real", "kinect_pyramid"),
    ("syn", "fandisk γ0.4 normal", "fandisk", 0.4, "normal"),
    ("syn", "fandisk γ0.4 random", "fandisk", 0.4, "random"),
    ("syn", "spot γ0.4 normal", "spot", 0.4, "normal"),
    ("syn", "spot γ0.4 random", "spot", 0.4, "random"),
    ("syn", "nicolo γ0.4 random", "nicolo", 0.4, "random"),
    ("syn", "rocker_arm γ0.3 normal", "rocker_arm", 0.3, "normal"),
    ("syn", "screwdriver γ0.3 normal", "screwdriver", 0.3, "normal"),
    ("syn", "camelhead γ0.3 normal", "camelhead", 0.3, "normal"),
    ("corr", "spot correlated m=4 γ0.5", "spot", 0.5, 4),
    ("corr", "rocker_arm correlated m=4 γ0.5", "rocker_arm", 0.5, 4),
    ("corr", "camelhead correlated m=8 γ0.6", "camelhead", 0.6, 8),
]


def mean_angle(V, V_ref, F) -> float:
    """E_a: mean angle (degrees) between corresponding face normals."""
    from meshrepair.metrics import mean_angle_error

    return mean_angle_error(V, V_ref, F)


def load(c):
    from meshrepair import add_noise

    if c[0] == "pair":
        Vn, F, _ = C.read(c[2])
        Vt, _, _ = C.read(c[3])
        return Vn, Vt, F
    Vt, F, _ = C.read(c[2])
    if c[0] == "syn":
        return add_noise(Vt, F, c[3], direction=c[4], seed=7), Vt, F
    C.CACHE.mkdir(parents=True, exist_ok=True)
    f = C.CACHE / f"corr_{c[2]}_g{c[3]:g}_m{c[4]}_s7.npy"
    if not f.exists():
        from meshrepair.denoise.scale import correlated_noise

        np.save(f, correlated_noise(Vt, F, c[3], c[4], seed=7))
    return np.load(f), Vt, F


def run(only: str | None = None) -> list[dict]:
    from meshrepair import denoise, msae, vertex_error

    rows = []
    for c in CASES:
        if only and only not in c[1]:
            continue
        Vn, Vt, F = load(c)
        t = time.perf_counter()
        r = denoise(Vn, F)
        dt = time.perf_counter() - t
        rows.append(dict(name=c[1], set="design" if c[1] in DESIGN else "held out",
                         msae_in=msae(Vn, Vt, F), msae=msae(r.V, Vt, F),
                         ea=mean_angle(r.V, Vt, F), ev=vertex_error(r.V, Vt), time=dt,
                         iters=r.iterations,
                         params={k: v for k, v in r.params.items()
                                 if isinstance(v, (bool, int, float, str))}))
        print(json.dumps(rows[-1], ensure_ascii=False), flush=True)
    return rows


def table(before: list[dict], now: list[dict]) -> str:
    b = {r["name"]: r for r in before}
    out = ["| case | set | noisy MSAE | before MSAE / E_a | now MSAE / E_a | now / before | "
           "E_V before → now |", "|---|---|---:|---|---|---:|---|"]
    for r in sorted(now, key=lambda r: r["name"] not in DESIGN):
        o = b.get(r["name"])
        if o is None:
            continue
        kind = "design" if r["name"] in DESIGN else "held out"
        out.append(f"| {r['name']} | {kind} | {r['msae_in']:.1f} | {o['msae']:.1f} / "
                   f"{o['ea']:.2f}° | **{r['msae']:.1f}** / {r['ea']:.2f}° | "
                   f"{r['msae'] / o['msae']:.2f} | {o['ev']:.2e} → {r['ev']:.2e} |")
    return "\n".join(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", help="write the rows here")
    ap.add_argument("--only", help="substring of the case names to run")
    ap.add_argument("--table", nargs=2, metavar=("BEFORE", "NOW"),
                    help="print the markdown comparison of two JSON files and exit")
    args = ap.parse_args(argv)
    if args.table:
        print(table(*(json.loads(Path(p).read_text()) for p in args.table)))
        return
    C.limit_threads(1)
    info = C.machine_info()
    print(f"# memory probe {info['memprobe_ms']} ms, git {info['git']}, pkg {info['pkg']}")
    C.warm_imports()
    rows = run(args.only)
    if args.json:
        C.write_text(args.json, json.dumps(rows, ensure_ascii=False, indent=1))


if __name__ == "__main__":
    main()
