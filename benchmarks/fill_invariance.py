"""Does ``fill_holes`` depend on how the mesh is numbered or placed?

For each shared mesh: cut 3 geodesic discs (``meshrepair.synthetic.cut_holes``, radius r in mean
edge lengths, seed 0), fill the cut mesh, a relabelled copy (vertices and faces permuted), a copy
scaled by 37.3 and a rotated and translated copy, and print the number of new vertices of each
fill and the largest distance, over the bounding-box diagonal, between the original fill's
vertices and the others' (old vertices by index, new vertices to the nearest new vertex).
Equal counts and distances at rounding level mean the patches are the same.

    python benchmarks/fill_invariance.py [--radius 8] [--meshes fandisk,bunny,...]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402
import numpy as np  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

import meshrepair as mr  # noqa: E402
from meshrepair.synthetic import cut_holes  # noqa: E402

MESHES = "fandisk,bunny,rocker_arm,nefertiti,igea"


def _apart(a: np.ndarray, b: np.ndarray, n: int, diag: float) -> float:
    """Largest move of ``b`` against ``a`` (old vertices by index, new ones to the nearest)."""
    old = float(np.abs(b[:n] - a[:n]).max())
    if len(a) != len(b) or len(a) == n:
        return old / diag if len(a) == len(b) else float("nan")
    new = max(cKDTree(a[n:]).query(b[n:])[0].max(), cKDTree(b[n:]).query(a[n:])[0].max())
    return max(old, float(new)) / diag


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--radius", type=float, default=8.0, help="disc radius in l̄ (default 8)")
    ap.add_argument("--meshes", default=MESHES, help=f"shared meshes (default {MESHES})")
    args = ap.parse_args()
    print("machine:", C.machine_info())
    print(f"\nfill_holes of 3 cut discs of {args.radius:g} l̄ (seed 0): new vertices of the fill "
          "of the mesh / relabelled / ×37.3 / rotated and moved; largest move / diag\n")
    print("| mesh | new vertices | relabelled | scaled | rotated |")
    print("|---|---|---:|---:|---:|")
    for name in args.meshes.split(","):
        V, F, _ = C.read(name)
        V, F = cut_holes(V, F, args.radius, seed=0)[:2]
        n = len(V)
        diag = float(np.linalg.norm(np.ptp(V, axis=0)))
        a = mr.fill_holes(V, F).V
        rng = np.random.default_rng(1)
        p = rng.permutation(n)
        inv = np.empty(n, dtype=np.int64)
        inv[p] = np.arange(n)
        b = mr.fill_holes(V[p], inv[F][rng.permutation(len(F))]).V
        b = np.r_[b[:n][inv], b[n:]]
        s = 37.3
        c = mr.fill_holes(s * V, F).V / s
        R = Rotation.from_euler("xyz", [0.3, 1.1, -0.7]).as_matrix()
        t = np.array([5.0, -2.0, 11.0]) * diag
        d = (mr.fill_holes(V @ R.T + t, F).V - t) @ R
        counts = " / ".join(str(len(x) - n) for x in (a, b, c, d))
        print(f"| {name} | {counts} | " + " | ".join(f"{_apart(a, x, n, diag):.1e}"
                                                     for x in (b, c, d)) + " |", flush=True)


if __name__ == "__main__":
    main()
