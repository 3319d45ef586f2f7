"""Monotone in the noise, and against a tuned Taubin filter at low noise (issue 26's guard).

For every clean mesh of the shared set (``--meshes``), white Gaussian noise (32) along the
normals (``--direction``), or correlated noise of ``--correlated M`` umbrella steps, at each
level of ``--levels`` (mean edge lengths, seed 1): the MSAE
(deg²) of ``mr.denoise`` at its defaults, and of the best Taubin λ|μ filter over a grid of
pair counts (the oracle: it knows the truth), with the input's own MSAE. A row is flagged
``NOT MONOTONE`` where a higher level gives a lower MSAE than a lower one, ``> Taubin`` where
the defaults lose to the tuned filter and ``> input`` where their result is further from the
truth than the noisy input itself. The last two columns repeat both MSAEs over the truth's
well-shaped faces only (smallest interior angle at least ``--sliver-angle`` degrees,
:func:`meshrepair.min_face_angles`, the Taubin filter at the same pair count): a sliver's normal
turns by tens of degrees under noise of a fraction of an edge, and on meshes with slivers they
can decide the whole MSAE.

    python benchmarks/monotone.py                       # every mesh < 60k vertices, 4 levels
    python benchmarks/monotone.py --meshes bunny spot --levels 0.05 0.1 0.2 --json out.json
    python benchmarks/monotone.py --correlated 4 --levels 0.1 0.3 0.5   # correlated, ℓ ≈ 2 edges

``--peers`` adds the best of more oracle-tuned filters on each row: the in-house bilateral
normal filter and MeshLib's ``meshDenoiseViaNormals`` (when installed) over the grids of
``benchmarks/compare.py``, with Taubin's grid above; the row's ``best filter`` column is the
lowest MSAE of the three (each filter's grid point chosen with the truth) and the summary gives
the median ratio of the defaults to it, the rows above it and the rows above twice it:

    python benchmarks/monotone.py --levels 0.1 0.2 0.3 --peers
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

MESHES = ["fandisk", "twelve", "sharp_sphere", "trim_star", "rocker_arm", "screwdriver",
          "bunny", "nicolo", "nefertiti", "camelhead", "spot", "kinect_pyramid"]
TAUBIN_PAIRS = (1, 2, 3, 5, 8, 12, 18, 27, 40, 60)


def tuned_taubin(Vn, F, Vt, faces=None):
    """The best Taubin filter's MSAE and pair count, and its MSAE over ``faces`` (a mask)."""
    from meshrepair.baselines import taubin_smooth
    from meshrepair.metrics import msae

    best = (float("inf"), 0, float("nan"))
    for k in TAUBIN_PAIRS:
        X = taubin_smooth(Vn, F, iterations=k)
        m = msae(X, Vt, F)
        if m < best[0]:
            best = (m, k, msae(X, Vt, F, faces=faces) if faces is not None else float("nan"))
    return best


def oracle_peers(Vn, F, Vt, methods, name: str = ""):
    """``(MSAE, label)`` of the best run over the grids of ``methods`` (compare.py ``Method``s)
    on the noisy ``Vn`` against the truth ``Vt``, each grid point run and scored by compare.py's
    ``run_one`` (runs that fail or change the connectivity are left out)."""
    import compare

    case = compare.Case(name, "monotone", Vn, Vt, F, "monotone.py")
    best = (float("inf"), "-")
    for m in methods:
        b = compare.MethodResult(m, compare.Run({}, error="not run"),
                                 [compare.run_one(m, case, kw) for kw in m.grid]).best("msae")
        if b is not None and b.msae < best[0]:
            best = (b.msae, m.short)
    return best


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="*", default=MESHES)
    ap.add_argument("--levels", nargs="*", type=float, default=[0.05, 0.1, 0.2, 0.3])
    ap.add_argument("--direction", default="normal", choices=["normal", "random"])
    ap.add_argument("--correlated", type=int, default=0, metavar="M",
                    help="correlated noise along the normals instead: M umbrella steps of white "
                         "noise (scale.correlated_noise, length ≈ √M edges), level γ")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--json", help="write the rows as JSON")
    ap.add_argument("--sliver-angle", type=float, default=5.0,
                    help="faces of the truth with a smaller interior angle (degrees) are left out "
                         "of the last two columns (default 5)")
    ap.add_argument("--peers", action="store_true",
                    help="also the best oracle-tuned bilateral normal filter and MeshLib "
                         "meshDenoiseViaNormals (grids of compare.py) on each row")
    args = ap.parse_args(argv)
    C.limit_threads(1)
    import meshrepair as mr

    peers = []
    if args.peers:
        import compare

        notes: list[str] = []
        peers = [m for m in compare.inhouse_methods() + compare.meshlib_methods(notes)
                 if m.name in ("bilateral_normal_filter", "meshDenoiseViaNormals")]
        for n in notes:
            print(n)

    rows = []
    print("| mesh | γ | input MSAE | defaults MSAE | tuned Taubin MSAE (pairs) | ratio | flags | "
          "slivers | defaults / Taubin without them |"
          + (" best filter MSAE | ratio |" if peers else ""))
    print("|---|---:|---:|---:|---:|---:|---|---:|---|" + ("---:|---:|" if peers else ""))
    for name in args.meshes:
        Vt, F, _ = C.read(name)
        shaped = mr.min_face_angles(Vt, F) >= args.sliver_angle
        prev = None
        for g in args.levels:
            if args.correlated:
                from meshrepair.denoise.scale import correlated_noise

                Vn = correlated_noise(Vt, F, g, args.correlated, seed=args.seed)
            else:
                Vn = mr.add_noise(Vt, F, g, direction=args.direction, seed=args.seed)
            t = time.perf_counter()
            r = mr.denoise(Vn, F)
            dt = time.perf_counter() - t
            m = mr.msae(r.V, Vt, F)
            m_in = mr.msae(Vn, Vt, F)
            mt, kt, mts = tuned_taubin(Vn, F, Vt, shaped)
            ms = mr.msae(r.V, Vt, F, faces=shaped)
            flags = []
            if prev is not None and m < prev:
                flags.append("NOT MONOTONE")
            if m > mt:
                flags.append("> Taubin")
            if m > m_in:
                flags.append("> input")
            prev = m
            bp = oracle_peers(Vn, F, Vt, peers, f"{name} {g:g}") if peers else (float("inf"), "-")
            best, who = (mt, "Taubin") if mt <= bp[0] else bp
            rows.append({"mesh": name, "gamma": g, "direction": args.direction,
                         "best_filter": best, "best_filter_name": who,
                         "correlated": args.correlated, "msae": m, "msae_input": m_in,
                         "taubin": mt, "taubin_pairs": kt, "seconds": dt,
                         "slivers": int((~shaped).sum()), "msae_shaped": ms,
                         "taubin_shaped": mts,
                         "willmore_weight": r.params.get("willmore_weight"),
                         "presmooth_steps": r.params.get("presmooth_steps"),
                         "flags": flags})
            extra = f" {best:.2f} ({who}) | {m / best:.2f} |" if peers else ""
            print(f"| {name} | {g:g} | {m_in:.2f} | {m:.2f} | {mt:.2f} ({kt}) | {m / mt:.2f} | "
                  f"{', '.join(flags)} | {int((~shaped).sum())} | {ms:.2f} / {mts:.2f} |{extra}",
                  flush=True)
    ratios = np.array([r["msae"] / r["taubin"] for r in rows])
    nm = sum("NOT MONOTONE" in r["flags"] for r in rows)
    ni = sum("> input" in r["flags"] for r in rows)
    print(f"\nmedian ratio to tuned Taubin {np.median(ratios):.2f}; worse than Taubin in "
          f"{int((ratios > 1).sum())} of {len(rows)}; non-monotone steps {nm}; worse than the "
          f"input in {ni}")
    rs = np.array([r["msae_shaped"] / r["taubin_shaped"] for r in rows])
    print(f"without slivers (< {args.sliver_angle:g}°): median ratio {np.median(rs):.2f}; worse "
          f"than Taubin in {int((rs > 1).sum())} of {len(rows)}")
    if peers:
        rb = np.array([r["msae"] / r["best_filter"] for r in rows])
        worse = [f"{r['mesh']} {r['gamma']:g} ({x:.2f}, {r['best_filter_name']})"
                 for r, x in zip(rows, rb, strict=True) if x > 1]
        print(f"against the best oracle-tuned filter (Taubin, bilateral, MeshLib): median ratio "
              f"{np.median(rb):.2f}, largest {rb.max():.2f}; above it in {len(worse)} of "
              f"{len(rows)}{': ' + ', '.join(worse) if worse else ''}; above twice it in "
              f"{int((rb > 2).sum())}")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
