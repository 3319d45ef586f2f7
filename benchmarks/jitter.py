"""Stability of the denoising decisions under a rounding-level jitter of the input (issue 26).

For every shared noisy case (``noisy/<stem>__<noise>.ply`` against its truth ``<stem>.ply``) and
every published triple (``published/<case>__noisy.ply`` against ``__truth.ply``), ``denoise(V, F)``
runs at its defaults on the input and on the input with every vertex moved by
``eps · diag`` (``diag`` = bounding-box diagonal, default ``eps = 1e-10``) in a random direction
(seeded). A denoiser whose decisions are not on knife edges gives the same MSAE (33) to about
``eps``; the table prints both MSAEs and the relative change ``MSAE_jitter / MSAE - 1`` per case,
then the largest and the median of ``|change|``.

    python benchmarks/jitter.py --quick            # three cases (CAD, organic, real Kinect)
    python benchmarks/jitter.py                    # every noisy and published case
    python benchmarks/jitter.py --only fandisk --eps 1e-8 --seed 3 --out table.md
    python benchmarks/jitter.py --decisions 0.5    # + the params that moved where |change| > 0.5 %
    python benchmarks/jitter.py --only fandisk__gauss0.7 --option n_solver=direct --probe-trace

``--option KEY=VALUE`` (repeatable) passes a keyword to ``denoise`` in both runs (values are
read as Python literals, else kept as strings); ``--probe-trace`` prints, per case, the relative
difference of the two runs' probe energies every 5 iterations (where the rounding grows), and
``--solve-trace`` the same for the last main solve of each run.

``--share-probe`` gives the jittered run the unjittered run's robust probe (its plan reads that
probe instead of running its own): what then moves comes from the main solve and the steps
after it, not from the crease support C. ``--seeds N`` runs N jitters (seeds ``seed`` ..
``seed + N - 1``) per case and adds the largest ``|change|`` over them and the range of the N + 1
MSAEs (input and jitters) over the input's MSAE: the spread of the result that a rounding-level
change of the input samples.

    python benchmarks/jitter.py --share-probe --solve-trace --only fandisk__gauss0.7
    python benchmarks/jitter.py --seeds 8

The machine's memory probe is printed with the table (benchmarks/_common.py).
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402, I001  (sets the thread env vars before numpy is imported)
import numpy as np  # noqa: E402

QUICK = ("noisy/fandisk__gauss0.3", "noisy/trim_star__gauss_n3", "published/tgv_kinect_pyramid")


def cases() -> list[tuple[str, str, str]]:
    """``(case, noisy path name, truth path name)`` for every shared noisy and published case."""
    out = []
    for p in sorted((C.MESHES / "noisy").glob("*__*.ply")):
        stem = p.name.split("__")[0]
        if (C.MESHES / f"{stem}.ply").exists():
            out.append((f"noisy/{p.stem}", f"noisy/{p.stem}", stem))
    for p in sorted((C.MESHES / "published").glob("*__noisy.ply")):
        case = p.name[: -len("__noisy.ply")]
        if (C.MESHES / "published" / f"{case}__truth.ply").exists():
            out.append((f"published/{case}", f"published/{case}__noisy",
                        f"published/{case}__truth"))
    if not out:
        raise SystemExit(f"no noisy or published cases under {C.MESHES}")
    return out


def jitter(V: np.ndarray, eps: float, seed: int) -> np.ndarray:
    """``V`` with every vertex moved by exactly ``eps · diag`` along a random unit direction."""
    rng = np.random.default_rng(seed)
    d = rng.standard_normal(V.shape)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    return V + (eps * diag) * d


def _trace(h0: list, h1: list) -> list[float]:
    """Relative difference of two runs' energies every 5 iterations."""
    return [abs(h1[i]["energy"] / h0[i]["energy"] - 1.0)
            for i in range(0, min(len(h0), len(h1)), 5)]


def _jittered_plan(Vj, F, p0, options: dict, share_probe: bool):
    """The plan of the jittered input: its own, or (``share_probe``) one that reads the
    unjittered plan ``p0``'s robust probe instead of running a probe."""
    from meshrepair import plan_denoise

    if not share_probe:
        return plan_denoise(Vj, F, **options)
    from meshrepair.denoise.analysis import REORDER_MIN_VERTICES, _plan
    from meshrepair.denoise.api import _OPTION_DEFAULTS

    if p0._state.r1 is None:
        raise SystemExit("--share-probe: the plan ran no probe (custom stages or regions=False)")
    if len(Vj) >= REORDER_MIN_VERTICES:  # the probe is in a coordinate-dependent vertex order
        raise SystemExit(f"--share-probe needs fewer than {REORDER_MIN_VERTICES} vertices")
    return _plan(Vj, F, probe_result=p0._state.r1, **{**_OPTION_DEFAULTS, **options})


def run(case, noisy, truth, eps: float, seed: int, options: dict | None = None, *,
        share_probe: bool = False, seeds: int = 1) -> dict:
    from meshrepair import denoise, msae, plan_denoise

    Vn, F, _ = C.read(noisy)
    Vt, Ft, _ = C.read(truth)
    if not np.array_equal(F, Ft):
        raise SystemExit(f"{noisy} and {truth} do not share faces")
    options = options or {}
    t = time.perf_counter()
    p0 = plan_denoise(Vn, F, **options)
    r0 = denoise(Vn, F, plan=p0)
    m0 = msae(r0.V, Vt, F)
    runs = []
    for s in range(seed, seed + seeds):
        Vj = jitter(Vn, eps, s)
        p1 = _jittered_plan(Vj, F, p0, options, share_probe)
        r1 = denoise(Vj, F, plan=p1)
        runs.append((p1, r1, msae(r1.V, Vt, F)))
    p1, r1, m1 = runs[0]
    ms = np.array([m0] + [m for _, _, m in runs])
    return {"case": case, "nV": len(Vn), "msae": m0, "msae_jitter": m1,
            "change": m1 / m0 - 1.0, "time_s": time.perf_counter() - t,
            "max_change": float(np.max(np.abs(ms[1:] / m0 - 1.0))),
            "spread": float((ms.max() - ms.min()) / m0), "msae_range": (ms.min(), ms.max()),
            "moved": moved_params(r0.params, r1.params),
            "probe_trace": _trace(p0._state.r1.history, p1._state.r1.history),
            "solve_trace": _trace(r0.history, r1.history)}


def moved_params(p0: dict, p1: dict, rel: float = 1e-3) -> dict:
    """The scalar entries of ``params`` that differ by more than ``rel`` (relative) between the
    two runs, ``{name: (value, jittered value)}``: the decisions that sit on a knife edge."""
    out = {}
    for k in sorted(set(p0) & set(p1)):
        a, b = p0[k], p1[k]
        if isinstance(a, bool) or isinstance(b, bool) or isinstance(a, str):
            if a != b:
                out[k] = (a, b)
        elif isinstance(a, (int, float)) and isinstance(b, (int, float)):
            if abs(a - b) > rel * max(abs(a), abs(b), 1e-12):
                out[k] = (a, b)
    return out


def _fmt(x) -> str:
    return f"{x:.4g}" if isinstance(x, float) else str(x)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help=f"only {', '.join(QUICK)}")
    ap.add_argument("--only", help="regex on the case name")
    ap.add_argument("--eps", type=float, default=1e-10, help="jitter / bounding-box diagonal")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", help="also write the markdown table to this file")
    ap.add_argument("--decisions", type=float, default=None, metavar="PCT",
                    help="list the params that moved (> 0.1 %%) for cases whose |change| > PCT %%")
    ap.add_argument("--option", action="append", default=[], metavar="KEY=VALUE",
                    help="a denoise keyword for both runs (repeatable)")
    ap.add_argument("--probe-trace", action="store_true",
                    help="print the probe energies' relative difference every 5 iterations")
    ap.add_argument("--solve-trace", action="store_true",
                    help="print the main solve energies' relative difference every 5 iterations")
    ap.add_argument("--share-probe", action="store_true",
                    help="the jittered run reads the unjittered run's probe (no probe of its own)")
    ap.add_argument("--seeds", type=int, default=1, metavar="N",
                    help="N jitters per case (seeds seed .. seed+N-1): largest |change|, range")
    args = ap.parse_args(argv)
    options = dict(C.keyword_option(o) for o in args.option)
    if not (np.isfinite(args.eps) and args.eps > 0):
        raise SystemExit("--eps must be a positive finite number")
    if args.seeds < 1:
        raise SystemExit("--seeds must be at least 1")
    todo = cases()
    if args.quick:
        todo = [c for c in todo if c[0] in QUICK]
    if args.only:
        todo = [c for c in todo if re.search(args.only, c[0])]
    C.limit_threads(1)
    print(f"machine: {C.machine_info()}\n", flush=True)
    opts = "".join(f", {k}={v!r}" for k, v in options.items())
    if args.share_probe:
        opts += ", probe shared"
    many = args.seeds > 1
    seeds = f"s {args.seed}..{args.seed + args.seeds - 1}" if many else f" {args.seed}"
    extra = (" max |change| | MSAE range | range / MSAE |", "---:|---:|---:|") if many else ("", "")
    lines = [f"jitter {args.eps:g} · bounding-box diagonal per vertex, seed{seeds}{opts}", "",
             f"| case | #V | MSAE | MSAE jittered | change |{extra[0]} time (all runs) |",
             f"|---|---:|---:|---:|---:|{extra[1]}---:|"]
    for line in lines:
        print(line, flush=True)
    rows = []
    for case, noisy, truth in todo:
        r = run(case, noisy, truth, args.eps, args.seed, options, share_probe=args.share_probe,
                seeds=args.seeds)
        rows.append(r)
        cols = (f" {100 * r['max_change']:.3f} % | {r['msae_range'][0]:.3f}-"
                f"{r['msae_range'][1]:.3f} | {100 * r['spread']:.2f} % |") if many else ""
        line = (f"| {case} | {r['nV']} | {r['msae']:.3f} | {r['msae_jitter']:.3f} "
                f"| {100 * r['change']:+.3f} % |{cols} {r['time_s']:.1f} s |")
        lines.append(line)
        print(line, flush=True)
    a = np.abs([r["change"] for r in rows])
    tail = ["", f"|change|: max {100 * a.max():.3f} % ({rows[int(a.argmax())]['case']}), "
            f"median {100 * np.median(a):.3f} % over {len(rows)} cases"]
    if many:
        b = np.array([r["max_change"] for r in rows])
        tail.append(f"largest |change| over {args.seeds} jitters: max {100 * b.max():.3f} % "
                    f"({rows[int(b.argmax())]['case']}), median {100 * np.median(b):.3f} %; "
                    f"cases within 1 %: {int(np.sum(b <= 0.01))} of {len(rows)}")
    if args.decisions is not None:
        tail.append("")
        for r in rows:
            if abs(r["change"]) * 100 > args.decisions:
                moved = ", ".join(f"{k} {_fmt(a)} -> {_fmt(b)}" for k, (a, b) in r["moved"].items())
                tail.append(f"{r['case']} ({100 * r['change']:+.2f} %): {moved or 'none'}")
    for flag, key, what in ((args.probe_trace, "probe_trace", "probe"),
                            (args.solve_trace, "solve_trace", "main solve")):
        if flag:
            tail.append("")
            for r in rows:
                tail.append(f"{r['case']} {what} energy difference every 5 iterations: "
                            + " ".join(f"{x:.1e}" for x in r[key]))
    for line in tail:
        print(line, flush=True)
    if args.out:
        C.write_text(args.out, "\n".join(lines + tail) + "\n")


if __name__ == "__main__":
    main()
