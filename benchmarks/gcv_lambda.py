"""The plan's λ scaled by a factor, scored by generalized cross-validation (GCV) and the truth.

For every case, the plan of ``mr.plan_denoise`` runs with its fidelity weight λ (and the λ of its
low-passed and correlated sub-plans) multiplied by each of ``--factors``. Each run ``f_k`` is
scored without the truth by the GCV function of the normal component of its residual,

.. math:: \\mathrm{GCV}(k) = \\frac{n\\,\\sum_i \\langle f_k(Y)_i - Y_i, n_i\\rangle^2}
          {\\bigl(n - \\operatorname{div} f_k\\bigr)^2},
          \\qquad \\operatorname{div} f_k \\approx \\frac{1}{ε}
          \\sum_i b_i \\langle f_k(Y + ε\\, b \\odot n)_i - f_k(Y)_i, n_i\\rangle ,

``n_i`` the vertex normals of the default run's result, ``b`` one vector of standard normal
draws (seed 5, Monte-Carlo divergence) and ``ε`` = 0.005 l̄. GCV needs neither the noise level nor
the truth (for a linear smoother it is the classical criterion of Craven and Wahba); it assumes
white noise along the normals. Printed per case: the default MSAE, the MSAE at the factor GCV
picks, the best MSAE over the factors (the oracle), the GCV values and ``div f_k / n``. Each case
costs two runs per factor, the plans of the input and of the perturbed input.

    python benchmarks/gcv_lambda.py --meshes bunny spot --levels 0.05 0.1 --direction random
    python benchmarks/gcv_lambda.py --published
    python benchmarks/gcv_lambda.py --correlated 4 --meshes bunny --levels 0.1 0.3
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402

EPS = 0.005  # perturbation of the Monte-Carlo divergence, mean edge lengths


def scaled(plan, k: float):
    """``plan`` with every λ (its own, the low-passed run's, the correlated model's) times ``k``."""
    kw = {"lam": plan.lam * k}
    if plan.inner is not None:
        kw["inner"] = scaled(plan.inner, k)
    if plan.if_correlated is not None:
        kw["if_correlated"] = scaled(plan.if_correlated, k)
    return replace(plan, **kw)


def gcv_scan(Vt, Y, F, factors, seed: int = 5):
    """Rows ``(factor, GCV, MSAE, div/n)`` for the input ``Y`` of truth ``Vt``."""
    import meshrepair as mr
    from meshrepair.mesh.geometry import mean_edge_length, vertex_normals

    le = mean_edge_length(Y, F)
    n_v = len(Y)
    plan = mr.plan_denoise(Y, F)
    X1 = mr.denoise(Y, F, plan=plan).V
    nrm = vertex_normals(X1, F)
    b = np.random.default_rng(seed).standard_normal(n_v)[:, None] * nrm
    eps = EPS * le
    plan_b = mr.plan_denoise(Y + eps * b, F)
    rows = []
    for k in factors:
        X = X1 if k == 1 else mr.denoise(Y, F, plan=scaled(plan, k)).V
        Xb = mr.denoise(Y + eps * b, F, plan=scaled(plan_b, k)).V
        div = float((b * (Xb - X)).sum() / eps)
        res = float((((X - Y) * nrm).sum(axis=1) ** 2).sum())
        gcv = n_v * res / (n_v - div) ** 2 / le ** 2
        rows.append((k, gcv, mr.msae(X, Vt, F), div / n_v))
    return rows


def _cases(args):
    import meshrepair as mr

    if args.published:
        for path in sorted((C.MESHES / "published").glob("*__noisy.ply")):
            case = path.name.split("__")[0]
            noisy = mr.read_mesh(path)
            truth = mr.read_mesh(path.with_name(f"{case}__truth.ply"))
            yield case, truth.V, noisy.V, noisy.F
        return
    for name in args.meshes:
        Vt, F, _ = C.read(name)
        for g in args.levels:
            if args.correlated:
                from meshrepair.denoise.scale import correlated_noise

                Y = correlated_noise(Vt, F, g, args.correlated, seed=args.seed)
                kind = f"correlated {args.correlated}"
            else:
                Y = mr.add_noise(Vt, F, g, direction=args.direction, seed=args.seed)
                kind = args.direction
            yield f"{name} {kind} {g:g}", Vt, Y, F


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="*", default=["bunny", "spot", "rocker_arm"])
    ap.add_argument("--levels", nargs="*", type=float, default=[0.05, 0.1, 0.2])
    ap.add_argument("--direction", default="normal", choices=["normal", "random"])
    ap.add_argument("--correlated", type=int, default=0, metavar="M",
                    help="correlated noise of M umbrella steps instead (scale.correlated_noise)")
    ap.add_argument("--published", action="store_true", help="the shared published triples")
    ap.add_argument("--factors", nargs="*", type=float, default=[0.5, 1.0, 2.0, 4.0])
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    if 1.0 not in args.factors:
        args.factors = [1.0, *args.factors]
    C.limit_threads(1)
    print(f"machine: {C.machine_info()}\n")
    print("| case | default MSAE | GCV factor | its MSAE | ratio | oracle factor | oracle MSAE | "
          "GCV per factor | div/n per factor |")
    print("|---|---:|---:|---:|---:|---:|---:|---|---|")
    ratios = []
    for case, Vt, Y, F in _cases(args):
        rows = gcv_scan(Vt, Y, F, args.factors)
        d = next(r for r in rows if r[0] == 1.0)
        g = min(rows, key=lambda r: r[1])
        o = min(rows, key=lambda r: r[2])
        ratios.append(g[2] / d[2])
        print(f"| {case} | {d[2]:.2f} | {g[0]:g} | {g[2]:.2f} | {g[2] / d[2]:.2f} | {o[0]:g} | "
              f"{o[2]:.2f} | {' '.join(f'{r[1] * 1e3:.3f}' for r in rows)} | "
              f"{' '.join(f'{r[3]:.2f}' for r in rows)} |", flush=True)
    r = np.array(ratios)
    print(f"\n{len(r)} cases: MSAE at GCV's factor over the default's: median {np.median(r):.3f}, "
          f"lower in {(r < 0.99).sum()}, higher by > 1 % in {(r > 1.01).sum()}, largest "
          f"{r.max():.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
