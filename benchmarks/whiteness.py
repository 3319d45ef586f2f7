"""The white-noise test of :mod:`meshrepair.denoise.whiteness` on both populations.

For every case whose reading finds correlated noise (an automatic Willmore weight above 1), both
noise models run: the white model's plan and the correlated one's (``plan.if_correlated``).
Printed: the residual test of the white model's result (one-ring correlation ρ₁, level over γ̂),
the model the test keeps, and the MSAE of each model against the truth, so a row where the test
keeps the worse model is visible (``WRONG``). Cases read as white noise print one line and run
nothing.

Cases are ``w:mesh:γ[:seed]`` (white Gaussian noise along the normals, seed 1), ``c:mesh:γ:m
[:seed]`` (``correlated_noise`` with ``m`` umbrella steps, seed 7) and ``kinect`` (the real
Kinect scan of the published TGV triple)::

    python benchmarks/whiteness.py                 # the design split, then the check split
    python benchmarks/whiteness.py --cases w:bunny:0.1 c:fandisk:0.4:3

The thresholds were chosen on the design split (``DESIGN``) and are checked on ``CHECK``.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402, I001  (sets the thread env vars before numpy is imported)

DESIGN = ["w:trim_star:0.1", "w:trim_star:0.2", "w:bunny:0.1", "c:fandisk:0.4:3",
          "c:twelve:0.4:3", "c:bunny:0.4:3", "kinect"]
CHECK = ["w:trim_star:0.1:2", "w:trim_star:0.2:2", "w:bunny:0.1:2", "w:bunny:0.1:3",
         "w:spot:0.1:2", "w:camelhead:0.05", "w:nefertiti:0.05", "w:nicolo:0.05",
         "c:fandisk:0.5:2", "c:fandisk:0.5:3", "c:twelve:0.3:3", "c:twelve:0.5:3",
         "c:sharp_sphere:0.5:3", "c:screwdriver:0.5:2", "c:spot:0.3:3", "c:spot:0.4:3",
         "c:spot:0.5:3", "c:trim_star:0.3:3", "c:trim_star:0.5:3", "c:nicolo:0.5:3",
         "c:rocker_arm:0.4:3", "c:camelhead:0.4:3"]


def _inputs(case: str):
    import meshrepair as mr
    from meshrepair.denoise.scale import correlated_noise

    if case == "kinect":
        Vt = mr.read_mesh(C.mesh_path("published/tgv_kinect_pyramid__truth")).V
        m = mr.read_mesh(C.mesh_path("published/tgv_kinect_pyramid__noisy"))
        return Vt, m.V, m.F
    kind, name, g, *rest = case.split(":")
    Vt, F, _ = C.read(name)
    if kind == "w":
        seed = int(rest[0]) if rest else 1
        return Vt, mr.add_noise(Vt, F, float(g), direction="normal", seed=seed), F
    m = int(rest[0]) if rest else 3
    seed = int(rest[1]) if len(rest) > 1 else 7
    return Vt, correlated_noise(Vt, F, float(g), m, seed=seed), F


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="*", default=None)
    args = ap.parse_args(argv)
    C.limit_threads(1)
    import meshrepair as mr
    from meshrepair.denoise.whiteness import white_residual

    print(f"machine: {C.machine_info()}\n")
    splits = [("cases", args.cases)] if args.cases else [("design", DESIGN), ("check", CHECK)]
    for split, cases in splits:
        print(f"\n{split} split\n")
        print("| case | w | ρ₁ | level / γ̂ | kept | white MSAE | correlated MSAE | |")
        print("|---|---:|---:|---:|---|---:|---:|---|")
        wrong = 0
        for case in cases:
            Vt, Y, F = _inputs(case)
            t0 = time.perf_counter()
            p = mr.plan_denoise(Y, F)
            if p.if_correlated is None:
                print(f"| {case} | {p.willmore_weight:.3g} | read as white noise | | | | | |",
                      flush=True)
                continue
            rw = mr.denoise(Y, F, plan=replace(p, if_correlated=None))
            rc = mr.denoise(Y, F, plan=p.if_correlated)
            t = white_residual(Y, rw.V, F, p._state.topo.edges, p._state.gamma)
            mw, mc = mr.msae(rw.V, Vt, F), mr.msae(rc.V, Vt, F)
            kept = "white" if t.white else "correlated"
            bad = (mw > mc) if t.white else (mc > mw)
            wrong += bad
            print(f"| {case} | {p.if_correlated.willmore_weight:.3g} | {t.rho1:.3f} | "
                  f"{t.level_ratio:.3f} | {kept} | {mw:.2f} | {mc:.2f} | "
                  f"{'WRONG' if bad else ''} ({time.perf_counter() - t0:.0f} s) |", flush=True)
        print(f"\n{split}: the test keeps the worse model in {wrong} case(s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
