"""The noise reading (:func:`meshrepair.denoise.spectrum.read_noise`) on known noise.

On shared clean meshes: white Gaussian noise along the normals and in random directions
(``add_noise``) and correlated noise along the normals (``scale.correlated_noise``: ``m``
umbrella steps of white noise, correlation length ``ℓ = √m`` edges). The true level is the RMS of
the displacement's component along the clean mesh's vertex normals (in mean edge lengths; for
random directions ``γ/√3``), the true length ``√m`` (0 for white noise). Ratios are read / true;
a row passes when the level ratio is within [0.75, 1.25] and, for correlated noise, the length
ratio within [1/1.5, 1.5] (for white noise: read as not correlated, ``ℓ̂ ≤ 1`` edge).

Then every shared noisy input with a truth (noisy/ and published/, among them the real Kinect
pyramid: the true level is measured from the displacement, with its part finer than ``W^32``, and
the length is read from the pure displacement field laid on the truth) and the real scan (no
truth)::

    python benchmarks/noise_reading.py                        # design + check meshes
    python benchmarks/noise_reading.py --meshes fandisk --kinds corr4:0.5
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402, I001  (sets the thread env vars before numpy is imported)
import numpy as np  # noqa: E402

DESIGN = ("fandisk", "nicolo", "spot")
CHECK = ("trim_star", "bunny", "rocker_arm", "twelve", "camelhead")
KINDS = ("normal:0.05", "normal:0.2", "normal:0.5", "random:0.05", "random:0.2", "random:0.5",
         "corr4:0.3", "corr4:0.6", "corr8:0.6", "corr16:0.3", "corr16:0.6", "corr64:0.6")


def noisy(V, F, kind: str, seed: int):
    """``(V_noisy, true_length)`` for a kind ``normal:γ``, ``random:γ`` or ``corrM:γ``."""
    from meshrepair import add_noise
    from meshrepair.denoise.scale import correlated_noise

    name, g = kind.split(":")
    if name in ("normal", "random"):
        return add_noise(V, F, float(g), direction=name, seed=seed), 0.0
    m = int(name[4:])
    return correlated_noise(V, F, float(g), m, seed=seed), float(np.sqrt(m))


def true_level(Vn, V, F) -> float:
    from meshrepair.mesh.geometry import mean_edge_length, vertex_normals

    h = np.einsum("ij,ij->i", Vn - V, vertex_normals(V, F))
    return float(np.sqrt(np.mean(h * h)) / mean_edge_length(V, F))


def _smoothed(x, F, steps: int):
    """``W^steps x`` with the umbrella averaging ``W`` of the reading."""
    from meshrepair.denoise.spectrum import umbrella_operator
    from meshrepair.mesh.topology import edge_topology

    W = umbrella_operator(edge_topology(F, len(x)).edges, len(x))
    for _ in range(steps):
        x = W @ x
    return x


def row(mesh, kind, lvl, length, r, dt) -> str:
    rl = r.level / lvl if lvl > 0 else float("nan")
    if length > 0:
        rlen = r.length / length
        ok = 0.75 <= rl <= 1.25 and 1 / 1.5 <= rlen <= 1.5
        rlen_s = f"{rlen:.2f}"
    else:
        ok = 0.75 <= rl <= 1.25 and not r.correlated
        rlen_s = "-"
    return (f"| {mesh} | {kind} | {lvl:.3f} | {length:.2f} | {r.level:.3f} | {r.length:.2f} "
            f"| {rl:.2f} | {rlen_s} | {r.white_evidence:.2f} | {'yes' if ok else 'NO'} "
            f"| {dt:.1f} s |"), ok


def main(argv=None) -> None:
    from meshrepair import read_mesh
    from meshrepair.denoise.spectrum import read_noise

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="+", default=list(DESIGN + CHECK))
    ap.add_argument("--kinds", nargs="+", default=list(KINDS))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--no-real", action="store_true", help="skip the real inputs")
    ap.add_argument("--real-only", action="store_true", help="only the real inputs")
    args = ap.parse_args(argv)
    C.limit_threads(1)
    print(f"machine: {C.machine_info()}\n", flush=True)
    print("| mesh | noise | true level | true ℓ | read level | read ℓ | level ratio | ℓ ratio "
          "| white evidence | pass | time |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---|---:|", flush=True)
    passed: dict[str, list[bool]] = {}
    for mesh in [] if args.real_only else args.meshes:
        V, F, _ = C.read(mesh)
        for kind in args.kinds:
            Vn, length = noisy(V, F, kind, args.seed)
            t = time.perf_counter()
            r = read_noise(Vn, F)
            line, ok = row(mesh, kind, true_level(Vn, V, F), length, r, time.perf_counter() - t)
            passed.setdefault(mesh, []).append(ok)
            print(line, flush=True)
    print()
    for mesh, oks in passed.items():
        split = "design" if mesh in DESIGN else "check"
        print(f"{mesh} ({split}): {sum(oks)}/{len(oks)} rows pass")
    if args.no_real:
        return
    print("\nshared noisy inputs with a truth, and the real scan\n")
    print("| input | true normal level (part finer than W^32) | ℓ read on the pure displacement "
          "| read level | read ℓ | level ratio | white evidence |")
    print("|---|---:|---:|---:|---:|---:|---:|", flush=True)
    from jitter import cases

    for _, noisy_name, truth in cases():
        Vn, F, _ = C.read(noisy_name)
        Vt = read_mesh(C.mesh_path(truth)).V
        lvl = true_level(Vn, Vt, F)
        from meshrepair.mesh.geometry import mean_edge_length, vertex_normals

        nt = vertex_normals(Vt, F)
        eta = np.einsum("ij,ij->i", Vn - Vt, nt)
        pure = read_noise(Vt, F, field=eta)
        r = read_noise(Vn, F)
        fine = eta - _smoothed(eta, F, 32)
        fine_lvl = float(np.sqrt(np.mean(fine * fine)) / mean_edge_length(Vt, F))
        print(f"| {noisy_name} | {lvl:.3f} ({fine_lvl:.3f}) | {pure.length:.2f} "
              f"(level {pure.level:.3f}) "
              f"| {r.level:.3f} | {r.length:.2f} | {r.level / lvl:.2f} | {r.white_evidence:.2f} |",
              flush=True)
    Vs, Fs, _ = C.read("scans/rabbit_scan")
    r = read_noise(Vs, Fs)
    print(f"| scans/rabbit_scan | (no truth) | - | {r.level:.3f} | {r.length:.2f} | - "
          f"| {r.white_evidence:.2f} |")


if __name__ == "__main__":
    main()
