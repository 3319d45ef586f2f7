"""Ablation of the denoising defaults: what each ingredient of the schedule contributes.

Usage: python benchmarks/ablation.py [--quick] [--out docs/ablation_table.md]

Each column switches one ingredient off (or back to the paper's plain setting); rows are shared
meshes with the paper's noise protocol (seed 7) and the published noisy pairs. Entries are
MSAE (deg^2) of the result; lower is better.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from threadpoolctl import threadpool_limits

from meshrepair import add_noise, denoise, msae, read_mesh
from meshrepair.model.solver import Stage

SHARED = Path(__file__).resolve().parents[2] / "shared" / "meshes"

VARIANTS = {
    "default": {},
    "no unfold": {"unfold": False},
    "no chain filter": {"min_feature_edges": 1},
    "static mask": {"mask_update_every": 0},
    "lambda 0.1": {"lam": 0.1},
    "one stage (paper)": {"stages": (Stage(a=10.0, eps=1.2, beta2_ratio=20 / 12,
                                           mask="adaptive", max_iter=100, name="feature"),),
                          "mask_update_every": 3, "min_feature_edges": 1, "unfold": False},
}

CASES = [
    ("fandisk", "pub", "noisy/fandisk__gauss0.3.ply"),
    ("twelve", "pub", "noisy/twelve__impulsive0.5.ply"),
    ("nicolo", "pub", "noisy/nicolo__gauss0.2.ply"),
    ("fandisk", 0.4, "normal"),
    ("fandisk", 0.4, "random"),
    ("spot", 0.4, "normal"),
    ("spot", 0.4, "random"),
    ("nicolo", 0.4, "random"),
]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="only the first four cases")
    ap.add_argument("--out", default=None, help="also write the markdown table here")
    args = ap.parse_args(argv)
    cases = CASES[:4] if args.quick else CASES
    head = "| case | noisy | " + " | ".join(VARIANTS) + " |"
    lines = [head, "|" + "---|" * (len(VARIANTS) + 2)]
    print(head, flush=True)
    t0 = time.time()
    for stem, g, d in cases:
        truth = read_mesh(SHARED / f"{stem}.ply")
        if g == "pub":
            Vn = read_mesh(SHARED / d).V
            label = d.split("/")[-1].removesuffix(".ply")
        else:
            Vn = add_noise(truth.V, truth.F, g, direction=d, seed=7)
            label = f"{stem} γ={g} {d}"
        row = [label, f"{msae(Vn, truth.V, truth.F):.0f}"]
        for opts in VARIANTS.values():
            r = denoise(Vn, truth.F, **opts)
            row.append(f"{msae(r.V, truth.V, truth.F):.1f}")
        line = "| " + " | ".join(row) + " |"
        lines.append(line)
        print(line, flush=True)
    print(f"({time.time() - t0:.0f} s)", file=sys.stderr)
    if args.out:
        Path(args.out).write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    with threadpool_limits(1):
        sys.exit(main())
