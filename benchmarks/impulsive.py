"""Synthetic impulsive noise on the shared meshes, the main run started from the input vs from
the robust probe (docs/parameters.md: ``rules.warm_start_from_probe``).

Noise: 0.1 l Gaussian noise along the vertex normals on every vertex, then a fraction of the
vertices (10 % or 20 %) thrown along their normals by 1.0 l or 0.6 l times a standard normal
(l the mean edge length; seed 5). Prints one markdown row per case::

    python benchmarks/impulsive.py
"""

from __future__ import annotations

import importlib

import _common  # noqa: F401  (limits BLAS threads before numpy)

MESHES = ("fandisk", "sharp_sphere", "trim_star", "screwdriver", "rocker_arm", "camelhead", "spot")
LEVELS = ((0.1, 1.0), (0.2, 0.6))


def main() -> None:
    from meshrepair import denoise
    from meshrepair.metrics import msae
    from meshrepair.synthetic import impulsive_noise

    rules = importlib.import_module("meshrepair.denoise.rules")
    info = _common.machine_info()
    print(f"machine: {info}, memory probe {_common.memory_probe():.1f} ms\n")
    print("| mesh | thrown | impulsive | w_out | from the input | from the probe (rule) | change |")
    print("|---|---|---|---:|---:|---:|---:|")
    for stem in MESHES:
        V, F, _ = _common.read(stem)
        for frac, amp in LEVELS:
            Vn = impulsive_noise(V, F, frac, amp)
            rules.WARM_IMPULSIVE = False
            a = msae(denoise(Vn, F).V, V, F)
            rules.WARM_IMPULSIVE = True
            r = denoise(Vn, F)
            b = msae(r.V, V, F)
            p = r.params
            print(f"| {stem} | {100 * frac:.0f} % × {amp} l | {p['impulsive']} | "
                  f"{p['outside_weight']:g} | {a:.1f} | {b:.1f} | {100 * (b / a - 1):+.1f} % |",
                  flush=True)


if __name__ == "__main__":
    main()
