"""Synthetic Kinect-like (spatially correlated) noise on the shared meshes: the defaults with
and without the crease sharpening (``rules.SHARPEN``,
:mod:`meshrepair.denoise.modes`).

Noise: ``meshrepair.denoise.scale.correlated_noise`` with m = 3 diffusion steps (ℓ ≈ 1.7 edges) and
level γ = 0.4 (seed 7), the regime where the multi-scale estimate finds the noise correlated
(w > 1) as on the real Kinect scan; holdout.py's correlated rows (m = 4 / 8) read w = 1 and do
not exercise the rule. Prints one markdown row per mesh::

    python benchmarks/kinect_like.py

``--decision`` compares the sharpening decision on ``ρ_S > 1/2`` alone
(``rules.SHARPEN_FLAT_SUPPORT = False``) with the default one (the flat support,
:mod:`meshrepair.denoise.sharpen_decision`) instead of the step off / on, and prints the largest
set's
``ρ`` and ``φ``; ``--cases mesh:γ:m:seed ...`` replaces the default list (``kinect`` is the
real Kinect pyramid of ``published/``)::

    python benchmarks/kinect_like.py --decision --cases kinect fandisk:0.4:3:1 twelve:0.3:3:3
"""

from __future__ import annotations

import argparse
import importlib
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402, I001  (sets the thread env vars before numpy is imported)

MESHES = ("fandisk", "bunny", "igea", "nicolo", "spot", "sharp_sphere", "twelve", "trim_star")


def _inputs(case: str):
    from meshrepair import read_mesh
    from meshrepair.denoise.scale import correlated_noise

    if case == "kinect":
        Vt = read_mesh(C.mesh_path("published/tgv_kinect_pyramid__truth")).V
        m = read_mesh(C.mesh_path("published/tgv_kinect_pyramid__noisy"))
        return Vt, m.V, m.F
    name, g, steps, seed = (case.split(":") + ["0.4", "3", "7"][len(case.split(":")) - 1:])[:4]
    Vt, F, _ = C.read(name)
    return Vt, correlated_noise(Vt, F, float(g), int(steps), seed=int(seed)), F


def main(argv=None) -> None:
    from meshrepair import denoise, mean_angle_error, msae

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--decision", action="store_true",
                    help="the decision on rho_S alone against the default (not off / on)")
    ap.add_argument("--cases", nargs="+", default=list(MESHES))
    args = ap.parse_args(argv)
    rules = importlib.import_module("meshrepair.denoise.rules")
    C.limit_threads(1)
    info = C.machine_info()
    print(f"machine: {info}\n")
    if args.decision:
        print("| case | w | ρ_S alone: MSAE / E_a (kept) | default (kept) | change "
              "| ρ | φ "
              "| time ρ_S alone / default |")
        print("|---|---:|---|---|---:|---:|---:|---:|")
    else:
        print("| mesh | w | ℓ | without sharpening MSAE / E_a | with (default) | change | kept | "
              "time without / with |")
        print("|---|---:|---:|---|---|---:|---:|---:|")
    for case in args.cases:
        Vt, Vn, F = _inputs(case)
        runs = []
        for on in (False, True):
            if args.decision:
                rules.SHARPEN_FLAT_SUPPORT = on
            else:
                rules.SHARPEN = on
            t = time.perf_counter()
            r = denoise(Vn, F)
            runs.append((r, time.perf_counter() - t))
        rules.SHARPEN, rules.SHARPEN_FLAT_SUPPORT = True, True
        (r0, dt0), (r1, dt) = runs
        m0, m1 = msae(r0.V, Vt, F), msae(r1.V, Vt, F)
        a0, a1 = mean_angle_error(r0.V, Vt, F), mean_angle_error(r1.V, Vt, F)
        p = r1.params
        if args.decision:
            print(f"| {case} | {p['willmore_weight']:.1f} | {m0:.2f} / {a0:.2f}° "
                  f"({r0.params['sharpened']:.2f}) | {m1:.2f} / {a1:.2f}° ({p['sharpened']:.2f}) "
                  f"| {100 * (m1 / m0 - 1):+.1f} % | {p['sharpen_rho']:.3f} | "
                  f"{p['sharpen_flat']:.2f} | {dt0:.1f} / {dt:.1f} s |", flush=True)
        else:
            print(f"| {case} | {p['willmore_weight']:.1f} | {p['noise_length']:.2f} "
                  f"| {m0:.2f} / {a0:.2f}° | {m1:.2f} / {a1:.2f}° | {100 * (m1 / m0 - 1):+.1f} % "
                  f"| {p['sharpened']:.3f} | {dt0:.1f} / {dt:.1f} s |", flush=True)


if __name__ == "__main__":
    main()
