"""Synthetic Kinect-like (spatially correlated) noise on the shared meshes: the defaults with
and without the crease sharpening of round 9k (``denoise_rules.SHARPEN``, :mod:`meshrepair.modes`).

Noise: ``meshrepair.scale.correlated_noise`` with m = 3 diffusion steps (ℓ ≈ 1.7 edges) and
level γ = 0.4 (seed 7), the regime where the multi-scale estimate finds the noise correlated
(w > 1) as on the real Kinect scan; holdout.py's correlated rows (m = 4 / 8) read w = 1 and do
not exercise the rule. Prints one markdown row per mesh::

    python benchmarks/kinect_like.py
"""

from __future__ import annotations

import importlib
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402, I001  (sets the thread env vars before numpy is imported)

MESHES = ("fandisk", "bunny", "igea", "nicolo", "spot", "sharp_sphere", "twelve", "trim_star")


def main() -> None:
    from meshrepair import denoise, mean_angle_error, msae
    from meshrepair.scale import correlated_noise

    rules = importlib.import_module("meshrepair.denoise_rules")
    C.limit_threads(1)
    info = C.machine_info()
    print(f"machine: {info}\n")
    print("| mesh | w | ℓ | without sharpening MSAE / E_a | with (default) | change | kept | "
          "time without / with |")
    print("|---|---:|---:|---|---|---:|---:|---:|")
    for name in MESHES:
        Vt, F, _ = C.read(name)
        Vn = correlated_noise(Vt, F, 0.4, 3, seed=7)
        rules.SHARPEN = False
        t0 = time.perf_counter()
        r0 = denoise(Vn, F)
        dt0 = time.perf_counter() - t0
        rules.SHARPEN = True
        t = time.perf_counter()
        r1 = denoise(Vn, F)
        dt = time.perf_counter() - t
        m0, m1 = msae(r0.V, Vt, F), msae(r1.V, Vt, F)
        print(f"| {name} | {r1.params['willmore_weight']:.1f} | {r1.params['noise_length']:.2f} "
              f"| {m0:.2f} / {mean_angle_error(r0.V, Vt, F):.2f}° | {m1:.2f} / "
              f"{mean_angle_error(r1.V, Vt, F):.2f}° | {100 * (m1 / m0 - 1):+.1f} % | "
              f"{r1.params['sharpened']:.3f} | {dt0:.1f} / {dt:.1f} s |", flush=True)


if __name__ == "__main__":
    main()
