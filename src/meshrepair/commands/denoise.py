"""``meshrepair denoise``, ``noise``, ``metrics`` and ``demo``."""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

import numpy as np

from meshrepair.commands.common import (
    ProgressBar,
    make_folder,
    output_folder,
    output_path,
    run_outputs,
    write_json_log,
)

log = logging.getLogger(__name__)


def _write_history(path: Path | None, result, extra: dict, force: bool) -> None:
    if path is None:
        return
    data = {"history": result.history, "parameters": result.params, **extra}
    write_json_log(path, data, force=force)


def holes_note(V: np.ndarray, F: np.ndarray, out) -> str:
    """A one-line hint naming the holes ``denoise`` kept (boundary loops that are not the open
    border of a scan, :func:`meshrepair.holes.border.find_borders`), or ``""``."""
    from meshrepair.holes.border import find_borders
    from meshrepair.holes.detect import _find_holes

    holes = _find_holes(V, F)
    n = len(holes) - len(find_borders(V, F, holes))
    if n <= 0:
        return ""
    return (f"note: the mesh has {n} hole{'s' if n > 1 else ''} (boundary loops that are not an "
            f"open scan's border), kept as they are; 'meshrepair fill {out} FILLED.ply' fills "
            f"{'them' if n > 1 else 'it'}")


def run_denoise(args: argparse.Namespace) -> int:
    from meshrepair.denoise.api import denoise
    from meshrepair.io import read_mesh, write_like_input
    from meshrepair.model.solver import StopRequested

    if args.explain:
        return _explain(args)
    if args.output is None:
        from meshrepair.errors import MeshRepairError

        raise MeshRepairError("denoise needs an OUTPUT mesh (or --explain to print the plan "
                              "and write nothing)")
    out, log_path, report_path = run_outputs(args, [args.input], output=args.output)
    m = read_mesh(args.input)
    t0 = time.perf_counter()
    plan = read_with_progress(m.V, m.F, denoise_options(args, output=False), args.quiet)
    first, later = pass_lengths(plan)
    bar = ProgressBar(first, "denoise", enabled=not args.quiet, later=later)
    latest: dict = {}

    def cb(entry):
        bar(entry)
        latest["entry"] = entry

    try:
        r = denoise(m.V, m.F, plan=plan, callback=cb)
    except StopRequested:  # pragma: no cover - denoise returns on StopRequested
        raise
    finally:
        bar.close()
    dt = time.perf_counter() - t0
    if r.stop_reason == "interrupted" and not args.save_on_interrupt:
        print("interrupted: nothing written (pass --save-on-interrupt to keep the current "
              "iterate)", file=sys.stderr)
        return 130
    attrs = {}
    if args.save_mask:
        sharp_v = np.zeros(len(r.V), np.uint8)
        sharp_v[r.edges[r.M_E].ravel()] = 1
        attrs["sharp"] = sharp_v
    write_like_input(out, m, r, extra=attrs, force=args.force)
    _write_history(log_path, r, {"seconds": dt}, args.force)
    from meshrepair.commands import compiling

    print(f"denoised {len(r.V)} vertices in {r.iterations} iterations ({dt:.2f} s"
          f"{compiling.CLOCK.included()}, "
          f"{r.stop_reason}{bar.passes_note()}); noise estimate gamma={r.noise_estimate:.3f}, "
          f"lambda={r.params['lam']:.3g}, sharp edges {int(r.M_E.sum())}/{len(r.M_E)}")
    if r.stop_reason == "interrupted":
        print("interrupted: wrote the current iterate", file=sys.stderr)
    print(f"wrote {out}")
    note = holes_note(r.V, r.F, out)
    if note:
        print(note)
    if report_path is not None:
        from meshrepair.report.page import write_report

        write_report(report_path, title=f"meshrepair denoise {Path(args.input).name}",
                     input_mesh=(m.V, m.F), output_mesh=(r.V, r.F),
                     masks={"M_E": r.M_E}, history=r.history, parameters=r.params,
                     sharp_mask=r.M_E,
                     metrics={"noise estimate": r.noise_estimate, "iterations": r.iterations},
                     timings={"total s": dt}, overwrite=args.force)
        print(f"wrote {report_path}")
    return 0


def read_with_progress(V, F, options: dict, quiet: bool):
    """:func:`meshrepair.plan_denoise` with a progress counter ``reading`` of its probe's
    iterations (the probe of a large scan takes a while before the main solve starts; it stops
    by its own rule, so the counter has no total)."""
    from meshrepair.denoise.api import plan_denoise

    bar = ProgressBar(None, "reading", enabled=not quiet)
    try:
        return plan_denoise(V, F, **options, callback=bar)
    finally:
        bar.close()


def pass_lengths(plan) -> tuple[int, int]:
    """The progress bar's lengths for a run of ``plan``: the iterations of the solve that runs
    first (the plan of the low-passed input when the plan has one) and the most of any solve
    that may run after it (the correlated-noise or organic alternative, each one's stages
    summed); a solve stops earlier when its relative change falls below ``tol``."""
    def tree(p):
        yield p
        for q in (p.inner, p.if_correlated, p.if_structured):
            if q is not None:
                yield from tree(q)

    def length(p) -> int:
        return int(sum(s.max_iter for s in p.stages))

    start = plan.inner if plan.inner is not None else plan
    return length(start), max(length(q) for q in tree(plan))


def _explain(args: argparse.Namespace) -> int:
    """``denoise IN --explain``: the plan of the call, printed; nothing is written."""
    from meshrepair.denoise.api import plan_denoise
    from meshrepair.errors import MeshRepairError
    from meshrepair.io import read_mesh

    given = [n for n in ("output", "log", "report") if getattr(args, n, None)]
    if given:
        raise MeshRepairError(f"--explain writes nothing: drop {', '.join(given)}")
    m = read_mesh(args.input)
    t0 = time.perf_counter()
    plan = plan_denoise(m.V, m.F, **denoise_options(args, output=False))
    print(plan.explain())
    print(f"(read and planned in {time.perf_counter() - t0:.2f} s; nothing written)")
    return 0


def run_noise(args: argparse.Namespace) -> int:
    from types import SimpleNamespace

    from meshrepair.io import read_mesh, write_like_input
    from meshrepair.model.noise import add_noise

    out = output_path(args.output, [args.input], force=args.force)
    m = read_mesh(args.input)
    Vn = add_noise(m.V, m.F, args.gamma, direction=args.direction, seed=args.seed)
    write_like_input(out, m, SimpleNamespace(V=Vn, F=m.F), force=args.force)
    print(f"added noise gamma={args.gamma} ({args.direction}, seed {args.seed}); wrote {out}")
    return 0


def _metrics(V, F, Vr, Fr) -> dict:
    from meshrepair.commands.render import reference_metrics
    from meshrepair.metrics import distances

    d = distances(V, F, Vr, Fr)
    out = {}
    r = reference_metrics(V, F, Vr, Fr)
    if r is not None:
        out["MSAE (deg^2)"] = r["MSAE"]
        out["E_V"] = r["E_V"]
    out["mean distance"] = d["mean"]
    out["Hausdorff distance"] = d["hausdorff"]
    if d["diag"] > 0:  # a reference of zero size has no relative distances
        out["mean distance / bbox diagonal"] = d["mean"] / d["diag"]
        out["Hausdorff / bbox diagonal"] = d["hausdorff"] / d["diag"]
    return out


def run_metrics(args: argparse.Namespace) -> int:
    from meshrepair.io import read_mesh

    a, b = read_mesh(args.result), read_mesh(args.reference)
    vals = _metrics(a.V, a.F, b.V, b.F)
    if args.json:
        from meshrepair.atomic import json_text

        print(json_text(vals))
    else:
        for k, v in vals.items():
            print(f"{k:32s} {v:.6g}")
    if "MSAE (deg^2)" not in vals:  # a note for the reader: stdout stays JSON with --json
        print("(MSAE and E_V need the same connectivity; only distances were computed)",
              file=sys.stderr if args.json else sys.stdout)
    return 0


def run_demo(args: argparse.Namespace) -> int:
    from importlib.resources import files

    from meshrepair.denoise.api import denoise
    from meshrepair.io import read_mesh, write_mesh
    from meshrepair.metrics import msae, vertex_error

    data = files("meshrepair") / "data"
    names = ["fandisk_denoised.ply"] + ([] if args.no_render else ["fandisk_demo.png"])
    out, *rest = output_folder(args.outdir, names, [], force=args.force)
    png = rest[0] if rest else None
    noisy = read_mesh(str(data / "fandisk_noisy.ply"))
    truth = read_mesh(str(data / "fandisk.ply"))
    make_folder(args.outdir)
    print("meshrepair demo: feature-aware denoising of the fandisk CAD part")
    print("  input: published noisy fandisk (Gaussian noise, 0.3 mean edge lengths), "
          f"{len(noisy.V)} vertices")
    t0 = time.perf_counter()
    plan = read_with_progress(noisy.V, noisy.F, {}, args.quiet)
    first, later = pass_lengths(plan)
    bar = ProgressBar(first, "denoise", enabled=not args.quiet, later=later)
    r = denoise(noisy.V, noisy.F, plan=plan, callback=bar)
    bar.close()
    dt = time.perf_counter() - t0
    write_mesh(out, r.V, r.F, overwrite=args.force)
    m0, m1 = msae(noisy.V, truth.V, truth.F), msae(r.V, truth.V, truth.F)
    e0, e1 = vertex_error(noisy.V, truth.V), vertex_error(r.V, truth.V)
    print(f"  {'':10s} {'MSAE (deg^2)':>14s} {'E_V':>12s}")
    print(f"  {'noisy':10s} {m0:14.2f} {e0:12.3e}")
    print(f"  {'denoised':10s} {m1:14.2f} {e1:12.3e}")
    from meshrepair.commands import compiling

    print(f"  {r.iterations} iterations in {dt:.2f} s{compiling.CLOCK.included()}"
          f"{bar.passes_note()}; sharp edges kept: "
          f"{int(r.M_E.sum())}")
    print(f"  wrote {out}")
    if not args.no_render:
        try:
            from meshrepair.render import compare_figure

            compare_figure([(noisy.V, noisy.F), (r.V, r.F), (truth.V, truth.F)],
                           ["noisy", "meshrepair", "ground truth"],
                           metrics=[f"MSAE {m0:.1f}", f"MSAE {m1:.1f}", ""],
                           out_path=png, azimuth=35, elevation=25, width=400, height=400,
                           overwrite=args.force)
            print(f"  wrote {png}")
        except Exception as exc:  # the picture is a bonus; never fail the demo on it
            log.warning("could not render the demo picture: %s", exc)
    return 0


def add_denoise_options(p) -> None:
    """The denoising options, shared by ``meshrepair denoise`` and ``meshrepair batch``."""
    p.add_argument("--lam", type=float, default=None,
                   help="fidelity weight lambda (default: from the estimated noise level)")
    p.add_argument("--th", type=float, default=30.0, metavar="DEG",
                   help="sharp-edge dihedral threshold in degrees, in (0, 180)")
    p.add_argument("--robust-iters", type=int, default=None,
                   help="cap of the robust stage (default: 10-40 from the estimated noise)")
    p.add_argument("--feature-iters", type=int, default=60, metavar="N",
                   help="cap of the feature stage (iterations, >= 0)")
    p.add_argument("--tol", type=float, default=1e-6,
                   help="tolerance of the stopping rule (35) on the relative change, > 0")
    p.add_argument("--inner-solver", default="armijo",
                   choices=["armijo", "gd", "heavy_ball", "lbfgs", "bfgs"],
                   help="solver of the V-subproblem (26)")
    p.add_argument("--n-solver", default="auto", choices=["auto", "cg", "direct"],
                   help="N-subproblem (25) solver: block PCG, sparse direct, or chosen by size")
    p.add_argument("--save-mask", action="store_true",
                   help="store a per-vertex 'sharp' attribute (vertices on sharp edges) in the PLY")


def denoise_options(args: argparse.Namespace, *, output: bool = True) -> dict:
    """Keyword arguments of :func:`meshrepair.denoise` from the parsed options (plus
    ``save_mask``, an output option, when ``output``)."""
    kw = dict(lam=args.lam, th=args.th, robust_iters=args.robust_iters,
              feature_iters=args.feature_iters, inner_solver=args.inner_solver,
              n_solver=args.n_solver, tol=args.tol)
    if output:
        kw["save_mask"] = bool(args.save_mask)
    return kw


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "denoise", help="feature-aware denoising (keeps sharp creases)",
        description="Denoise a triangle mesh with the MC/edge-Willmore model and ADMM. Defaults "
                    "need no tuning: the noise level is estimated and every parameter is relative "
                    "to the mean edge length. Vertex order and faces are kept.")
    p.add_argument("input", help="noisy mesh (.ply .obj .off .stl)")
    p.add_argument("output", nargs="?",
                   help="result mesh (.ply recommended); never the input file (omitted with "
                        "--explain)")
    add_denoise_options(p)
    p.add_argument("--explain", action="store_true",
                   help="print the plan (what the input reads as, every decision and the rule "
                        "that made it, the stages) and write nothing")
    p.add_argument("--log", metavar="RUN.json",
                   help="write the iteration history and parameters as JSON")
    p.add_argument("--report", metavar="OUT.html", help="write a self-contained HTML report")
    p.add_argument("--save-on-interrupt", action="store_true",
                   help="on Ctrl-C, write the current iterate instead of nothing")
    p.add_argument("--force", action="store_true", help="overwrite OUTPUT if it exists")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run_denoise)

    p = subparsers.add_parser("noise", help="add the paper's noise model (32) to a mesh",
                              description="V0 = V + eta*d, eta ~ N(0, (gamma*mean edge)^2).")
    p.add_argument("input", help="clean mesh (.ply .obj .off .stl)")
    p.add_argument("output", help="noisy mesh to write; never the input file")
    p.add_argument("--gamma", type=float, default=0.3,
                   help="noise level in mean edge lengths, >= 0")
    p.add_argument("--direction", choices=["normal", "random"], default="normal",
                   help="displace along the vertex normals or in random directions")
    p.add_argument("--seed", type=int, default=0, help="random seed")
    p.add_argument("--force", action="store_true", help="overwrite OUTPUT if it exists")
    p.set_defaults(func=run_noise)

    p = subparsers.add_parser("metrics", help="MSAE, E_V and surface distances to a reference",
                              description="Compare RESULT with REFERENCE. MSAE (33) and E_V (34) "
                                          "need the same connectivity; distances do not.")
    p.add_argument("result", help="mesh to evaluate (e.g. a denoised mesh)")
    p.add_argument("reference", help="ground-truth mesh (same connectivity for MSAE and E_V)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.set_defaults(func=run_metrics)

    p = subparsers.add_parser("demo", help="denoise the bundled noisy fandisk and print errors",
                              description="Runs the default denoiser on a bundled noisy CAD part "
                                          "and prints MSAE/E_V before and after.")
    p.add_argument("--outdir", default="meshrepair-demo",
                   help="folder for the results (created if missing; default: %(default)s)")
    p.add_argument("--no-render", action="store_true", help="skip the PNG figure")
    p.add_argument("--force", action="store_true",
                   help="overwrite the results of an earlier run in --outdir")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run_demo)
