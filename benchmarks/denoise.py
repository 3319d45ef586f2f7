"""Speed / memory / accuracy benchmark of ``meshrepair.denoise`` (see docs/performance.md).

Usage (from the project root)::

    python benchmarks/denoise.py                      # full table + scaling up to ~1.2M vertices
    python benchmarks/denoise.py --quick              # table + scaling rows below 100k only
    python benchmarks/denoise.py --big                # also the ~4.7M-vertex scaling row
    python benchmarks/denoise.py --out docs/bench.md --json bench.json
    python benchmarks/denoise.py --only 'fandisk|twelve' --no-scaling
    python benchmarks/denoise.py --profile            # cProfile + per-phase breakdown, fandisk
    python benchmarks/denoise.py --profile scale:twelve:4 --iters 10   # same at 1.18M vertices
    python benchmarks/denoise.py --n-solver-table     # N-subproblem: CG vs sparse Cholesky/LU
    python benchmarks/denoise.py --vs-meshlib         # side by side with MeshLib (first/warm)
    python benchmarks/denoise.py --before old.json    # MSAE of an earlier run beside each row
    python -m cProfile -s tottime benchmarks/denoise.py --run-one noisy/fandisk__gauss0.3

Rows
----
* every shared noisy / ground-truth pair (published noise);
* synthetic noise (32), γ = 0.2 / 0.4, normal / random direction, seed 0, on fandisk, nicolo,
  spot, rocker_arm, screwdriver;
* scaling: a shared mesh (default ``twelve``) midpoint-subdivided 1..5 times (18k, 74k, 295k,
  1.18M, 4.7M vertices) with normal noise γ = 0.3; these runs are capped at ``--iters``
  ADMM iterations (half robust, half feature stage) and the total of a 100-iteration run is
  *extrapolated* as ``setup + 100 · s/iter``.

Measurement
-----------
Each case runs in a fresh process with BLAS limited to one thread. ``denoise(V, F)`` is called
with its defaults (only the scaling rows pass ``robust_iters`` / ``feature_iters``) ``--repeats``
times and the *minimum* is reported (the machine may be shared). Columns:

* ``s/iter``: ADMM loop time / iterations (from ``history[-1]["time"]``), min over repeats;
* ``total s``: wall time of the ``denoise`` call (validation, topology, noise estimate, unfolding
  and the ADMM loop; no I/O); ``setup s`` = total − loop;
* ``I/O s``: ``read_mesh`` of the input PLY + ``write_mesh`` of the result PLY (not in total);
* ``tracemalloc MB``: peak of memory traced by ``tracemalloc`` during one extra ``denoise`` call
  (numpy registers its buffers with tracemalloc, so this is numpy arrays + Python objects
  allocated during the call, excluding the input); for scaling rows ≥ 200k vertices this run is
  shortened to 2 + 4 iterations (the per-iteration working set repeats);
* ``RSS Δ MB``: resident high-water mark of the first timed call (VmHWM, reset just before it
  through ``/proc/self/clear_refs``; ``ru_maxrss`` where that is unavailable) − RSS just before
  it (same process, input already loaded): the real resident peak the call added, including
  allocator slack;
* ``MSAE``: mean squared angular error of face normals (deg², (33)) noisy → result;
  ``E_V``: (34) noisy → result.
"""

from __future__ import annotations

import argparse
import inspect
import json
import re
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402, I001  (sets the thread env vars before numpy is imported)
import numpy as np  # noqa: E402

PAIRS = [  # (name, noisy, truth)
    ("fandisk γ0.3 (published)", "noisy/fandisk__gauss0.3", "fandisk"),
    ("fandisk γ0.7 (published)", "noisy/fandisk__gauss0.7", "fandisk"),
    ("twelve impulsive 0.5", "noisy/twelve__impulsive0.5", "twelve"),
    ("sharp_sphere γ0.3", "noisy/sharp_sphere__gauss0.3", "sharp_sphere"),
    ("trim_star n3", "noisy/trim_star__gauss_n3", "trim_star"),
    ("bunny γ0.2", "noisy/bunny__gauss0.2", "bunny"),
    ("nicolo γ0.2", "noisy/nicolo__gauss0.2", "nicolo"),
    ("kinect_pyramid (real Kinect)", "noisy/kinect_pyramid__kinect_real", "kinect_pyramid"),
]
SYNTH_MESHES = ["fandisk", "nicolo", "spot", "rocker_arm", "screwdriver"]
SYNTH_NOISE = [(0.2, "normal"), (0.2, "random"), (0.4, "normal"), (0.4, "random")]
SCALE_GAMMA = 0.3


def build_cases(args) -> tuple[list[dict], list[dict]]:
    table, scaling = [], []
    for name, noisy, truth in PAIRS:
        table.append({"name": name, "kind": "pair", "noisy": noisy, "truth": truth})
    for m in SYNTH_MESHES:
        for g, d in SYNTH_NOISE:
            table.append({"name": f"{m} +γ{g} {d}", "kind": "synthetic", "truth": m,
                          "gamma": g, "direction": d, "seed": 0})
    for c in table:
        c["repeats"] = args.repeats
        c["trace"] = not args.no_trace
    levels = [int(x) for x in args.scale_levels.split(",")] if args.scale_levels else (
        [1, 2] if args.quick else [1, 2, 3, 4])
    if args.big and not args.scale_levels:
        levels.append(5)
    half = args.iters // 2
    for lv in levels:
        scaling.append({
            "name": f"{args.scale_base} ×{lv} subdiv +γ{SCALE_GAMMA}", "kind": "scaling",
            "base": args.scale_base, "levels": lv, "gamma": SCALE_GAMMA, "seed": 0,
            "denoise_kwargs": ({"robust_iters": half, "feature_iters": args.iters - half}
                               if args.iters > 0 else {}),
            "repeats": args.repeats if lv <= 3 else args.repeats_big,
            "trace": not args.no_trace,
            # the full run would double the cost of the big rows; the working set of one
            # iteration repeats, so 2 robust + 4 feature iterations (one mask refresh) suffice
            "trace_kwargs": ({"robust_iters": 2, "feature_iters": 4}
                             if lv >= 3 or args.iters <= 0 else None),
        })
    if args.only:
        rx = re.compile(args.only, re.I)
        table = [c for c in table if rx.search(c["name"])]
        scaling = [c for c in scaling if rx.search(c["name"])]
    if args.no_scaling:
        scaling = []
    if args.no_table:
        table = []
    return table, scaling


def _f(x, fmt="{:.2f}"):
    return "n/a" if x is None or (isinstance(x, float) and not np.isfinite(x)) else fmt.format(x)


def table_markdown(rows: list[dict], before: dict[str, float] | None = None) -> str:
    hdr = ("| case | nV | iters (stop) | s/iter | total s | setup s | I/O s (read+write) | "
           "tracemalloc peak MB | RSS Δ MB | MSAE noisy → result (deg²) | E_V noisy → result |")
    out = [hdr, "|---|---:|---|---:|---:|---:|---:|---:|---:|---|---|"]
    if before:
        out = [hdr + " MSAE before (Δ) |", out[1] + "---|"]
    for r in rows:
        if "error" in r:
            out.append(f"| {r['name']} | FAILED: {r['error'].splitlines()[-1][:120]} |")
            continue
        stop = {"rule (35)": "tol", "max_iter": "cap"}.get(r["stop_reason"], r["stop_reason"])
        out.append(
            f"| {r['name']} | {r['nV']:,} | {r['iterations']} ({stop}) | "
            f"{r['s_per_iter']:.4f} | {r['total_s']:.2f} | {r['setup_s']:.2f} | "
            f"{r['io_read_s'] + r['io_write_s']:.3f} | {_f(r.get('trace_peak_mb'), '{:.0f}')} | "
            f"{r['rss_delta_mb']:.0f} | {r['msae_in']:.1f} → {r['msae_out']:.2f} | "
            f"{r['ev_in']:.2e} → {r['ev_out']:.2e} |")
        if before:
            b = before.get(r["name"])
            out[-1] += (f" {b:.2f} ({100 * (r['msae_out'] / b - 1):+.2f} %) |" if b
                        else " n/a |")
    return "\n".join(out)


def scaling_markdown(rows: list[dict], iters_cap: int) -> str:
    hdr = ("| mesh | nV | nF | ADMM its run | s/iter | setup s | total s (measured) | "
           "total s for 100 its (**extrapolated**) | tracemalloc peak MB | RSS Δ MB | "
           "RSS peak MB | I/O s (read+write) | MSAE noisy → result (deg²) |")
    out = [hdr, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    good = []
    for r in rows:
        if "error" in r:
            out.append(f"| {r['name']} | FAILED: {r['error'].splitlines()[-1][:120]} |")
            continue
        good.append(r)
        capped = bool(r.get("denoise_kwargs"))
        extra = (f"{100 * r['s_per_iter'] + r['setup_s']:.0f}" if capped
                 else f"(measured: {r['iterations']} its, {r['stop_reason']})")
        tk = r.get("trace_kwargs") or {}
        traced = r.get("trace_peak_mb") is not None and np.isfinite(r["trace_peak_mb"])
        short = (" (short run)" if traced and tk.get("robust_iters", 0)
                 + tk.get("feature_iters", 0) < r["iterations"] else "")
        out.append(
            f"| {r['name']} | {r['nV']:,} | {r['nF']:,} | {r['iterations']} | "
            f"{r['s_per_iter']:.3f} | {r['setup_s']:.2f} | {r['total_s']:.1f} | {extra} | "
            f"{_f(r.get('trace_peak_mb'), '{:.0f}')}{short} | {r['rss_delta_mb']:.0f} | "
            f"{r['rss_peak_mb']:.0f} | {r['io_read_s'] + r['io_write_s']:.2f} | "
            f"{r['msae_in']:.1f} → {r['msae_out']:.2f} |")
    if len(good) >= 2:
        n = np.array([r["nV"] for r in good], float)
        s = np.array([r["s_per_iter"] for r in good], float)
        k, c = np.polyfit(np.log(n), np.log(s), 1)
        order = np.argsort(n)
        loc = [f"{int(n[a]):,}→{int(n[b]):,}: {np.log(s[b] / s[a]) / np.log(n[b] / n[a]):.2f}"
               for a, b in zip(order[:-1], order[1:], strict=True)]
        out.append("")
        out.append("Local log-log slopes of s/iter between successive sizes: " + "; ".join(loc)
                   + ". Per-vertex cost (µs / vertex / iteration): "
                   + ", ".join(f"{1e6 * s[i] / n[i]:.2f}" for i in order) + ".")
        out.append(f"Fitted s/iter ≈ {np.exp(c):.3g} · nV^{k:.3f} (log-log least squares over "
                   f"{len(good)} sizes, {int(n.min()):,}–{int(n.max()):,} vertices).")
        m = [r for r in good if r.get("trace_peak_mb") and np.isfinite(r["trace_peak_mb"])]
        if len(m) >= 2:
            km, _ = np.polyfit(np.log([r["nV"] for r in m]),
                               np.log([r["trace_peak_mb"] for r in m]), 1)
            kib = 1024 * m[-1]["trace_peak_mb"] / m[-1]["nV"]
            out.append(f"Memory: tracemalloc peak ≈ {kib:.2f} KiB/vertex at the largest size "
                       f"(log-log slope {km:.2f}).")
    if iters_cap > 0:
        out.append(f"\nScaling runs are capped at {iters_cap} ADMM iterations (half robust, "
                   "half feature stage); the 100-iteration total is setup + 100 × s/iter "
                   "(extrapolated, not measured).")
    else:
        out.append("\nScaling runs use the full default schedule (no iteration cap).")
    return "\n".join(out)


# --------------------------------------------------------------------------------------------
# profiling (in process)
# --------------------------------------------------------------------------------------------

def _load_for_profile(what: str):
    if what.startswith("scale:"):
        _, base, lv = what.split(":")
        C.generate_subprocess(base, int(lv), SCALE_GAMMA)
        _, Vn, F, _, _ = C.subdivided_noisy(base, int(lv), SCALE_GAMMA)
        return Vn, F
    V, F, _ = C.read(what)
    return V, F


def _profile_kwargs(what: str, iters: int) -> dict:
    return ({"robust_iters": iters // 2, "feature_iters": iters - iters // 2}
            if what.startswith("scale:") else {})


class PhaseTimer:
    """Attribute the wall time of the ADMM loop to its steps, from outside.

    Every function the solver loop calls through its namespace (functions imported into
    ``meshrepair.model.solver.admm``, functions of ``meshrepair`` modules it references, methods of
    the
    ``meshrepair`` classes it uses) is wrapped with a timer; nested calls count for the outermost
    wrapped call. The step in progress is switched at a few stable anchors of the scheme (17)-(21):
    the denoise callback (end of an iteration -> t-update), ``t_update`` or ``t_from_normals`` exit
    (-> N-update),
    ``run_inner`` (V-update), its exit (-> multipliers), ``ADMMSolver._mask``,
    ``ADMMSolver.energy``. Unwrapped numpy code between wrapped calls goes to the step in
    progress, so the steps add up to the solver time. Anchors that no longer exist are reported.
    """

    T, N, V, MU = ("t-update (17) incl. D·N",
                   "N-update (18)/(25): assemble, RHS, solve, normalise",
                   "V-update (19)/(26): inner solver",
                   "multipliers (20)-(21), residuals, rel. change")
    H = "history energy (6) + entry"
    ON_ENTER = {"run_inner": V, "ADMMSolver._mask": "mask M_E (dihedral threshold, chains)",
                "ADMMSolver.energy": H, "_kernels.reg_energy": H,
                "_fused.lengths_reg_energy": "new edge lengths + history energy (6) + entry",
                "TangentialRelaxer.step": "tangential relaxation"}
    ON_EXIT = {"t_update": N, "t_from_normals": N, "run_inner": MU, "TangentialRelaxer.step": MU,
               "ADMMSolver._mask": T}
    # (alternatives: the history energy was ADMMSolver.energy, then _kernels.reg_energy)
    ANCHORS = ("t_update|t_from_normals", "run_inner", "ADMMSolver._mask",
               "ADMMSolver.energy|_kernels.reg_energy|_fused.lengths_reg_energy")

    def __init__(self):
        self.depth = 0
        self.phase = "solver setup (centre/scale, first normals)"
        self.last = None
        self.solve_s = 0.0  # all solver runs of the call (the robust probe and the main run)
        self.n_solves = 0
        self.acc: dict[str, float] = {}
        self.fn_time: dict[str, float] = {}
        self.fn_calls: dict[str, int] = {}
        self.wrapped: set[str] = set()
        self._undo = []

    def _tick(self):
        now = time.perf_counter()
        if self.last is not None:
            self.acc[self.phase] = self.acc.get(self.phase, 0.0) + now - self.last
        self.last = now

    def on_iteration(self, entry):  # the denoise callback: an iteration ended
        if self.last is not None:
            self._tick()
            self.phase = self.T

    def _wrap(self, owner, attr: str, label: str):
        orig = owner.__dict__.get(attr) if isinstance(owner, type) else getattr(owner, attr, None)
        if not inspect.isfunction(orig) and not callable(orig):
            return
        tm = self

        def wrapper(*a, **k):
            if tm.depth or tm.last is None:
                return orig(*a, **k)
            tm._tick()
            if label in tm.ON_ENTER:
                tm.phase = tm.ON_ENTER[label]
            t0 = time.perf_counter()
            tm.depth += 1
            try:
                return orig(*a, **k)
            finally:
                tm.depth -= 1
                dt = time.perf_counter() - t0
                tm.fn_time[label] = tm.fn_time.get(label, 0.0) + dt
                tm.fn_calls[label] = tm.fn_calls.get(label, 0) + 1
                tm._tick()
                if label in tm.ON_EXIT:
                    tm.phase = tm.ON_EXIT[label]

        setattr(owner, attr, wrapper)
        self._undo.append((owner, attr, orig))
        self.wrapped.add(label)

    def install(self):
        import dataclasses

        import meshrepair.model.solver.admm as solver

        def ours(o):
            return (getattr(o, "__module__", "") or "").startswith("meshrepair")

        for name, obj in list(vars(solver).items()):
            if (inspect.isfunction(obj) and ours(obj) and name != "_drop_short_chains"
                    and name != "heap_allocations"):
                self._wrap(solver, name, name)
            elif inspect.ismodule(obj) and obj.__name__.startswith("meshrepair."):
                for fn, f in list(vars(obj).items()):
                    if inspect.isfunction(f) and not fn.startswith("_"):
                        self._wrap(obj, fn, f"{obj.__name__.split('.')[-1]}.{fn}")
            elif (inspect.isclass(obj) and obj.__module__.startswith("meshrepair")
                  and not dataclasses.is_dataclass(obj) and not issubclass(obj, BaseException)):
                for mn, m in list(vars(obj).items()):
                    if (inspect.isfunction(m) and not mn.startswith("__")
                            and (obj.__name__, mn) not in {("ADMMSolver", "solve"),
                                                           ("ADMMSolver", "_solve"),
                                                           ("ADMMSolver", "with_options")}):
                        self._wrap(obj, mn, f"{obj.__name__}.{mn}")
        orig_solve = solver.ADMMSolver.solve
        tm = self

        def solve(self_, *a, **k):
            tm.last = time.perf_counter()
            t0 = tm.last
            try:
                return orig_solve(self_, *a, **k)
            finally:
                tm._tick()
                tm.solve_s += time.perf_counter() - t0
                tm.n_solves += 1
                tm.last = None

        solver.ADMMSolver.solve = solve
        self._undo.append((solver.ADMMSolver, "solve", orig_solve))

    def uninstall(self):
        for owner, attr, orig in reversed(self._undo):
            setattr(owner, attr, orig)
        self._undo.clear()


def breakdown(what: str, iters: int) -> str:
    from meshrepair import denoise

    V, F = _load_for_profile(what)
    kw = _profile_kwargs(what, iters)
    denoise(V, F, **kw)  # warm-up (lazy imports, compiled kernels)
    t = time.perf_counter()
    denoise(V, F, **kw)
    plain = time.perf_counter() - t
    best = None
    for _ in range(3 if len(V) < 200_000 else 1):
        tm = PhaseTimer()
        tm.install()
        try:
            t = time.perf_counter()
            res = denoise(V, F, callback=tm.on_iteration, **kw)
            total = time.perf_counter() - t
        finally:
            tm.uninstall()
        if best is None or total < best[0]:
            best = (total, tm, res)
    total, tm, res = best
    # the steps accumulate over every solver run of the call (probe + main): so do the
    # iterations (one inner solve each) and the solver time
    it = tm.fn_calls.get("run_inner", res.iterations)
    lines = [f"Per-iteration breakdown, `{what}` ({len(V):,} vertices), default denoise"
             f"{' ' + str(kw) if kw else ''}: {it} ADMM iterations in {tm.n_solves} solver "
             f"run(s) (main run {res.iterations}); instrumented denoise "
             f"{total:.2f} s (uninstrumented {plain:.2f} s), solver loops {tm.solve_s:.2f} s, "
             f"setup outside the solvers (validation, topology, ordering, noise statistics, "
             f"regions, unfolding) {total - tm.solve_s:.2f} s.",
             "", "| step | total s | ms / iteration | share of solver |", "|---|---:|---:|---:|"]
    for ph, s in sorted(tm.acc.items(), key=lambda x: -x[1]):
        lines.append(f"| {ph} | {s:.3f} | {1e3 * s / max(it, 1):.2f} | "
                     f"{100 * s / tm.solve_s:.1f} % |")
    lines += ["", "Calls made by the solver loop (inclusive time of the outermost wrapped call):",
              "", "| function | calls | total s | ms / call |", "|---|---:|---:|---:|"]
    for f, s in sorted(tm.fn_time.items(), key=lambda x: -x[1]):
        n = tm.fn_calls[f]
        lines.append(f"| {f} | {n} | {s:.3f} | {1e3 * s / n:.3f} |")
    missing = [a for a in tm.ANCHORS if not any(x in tm.fn_calls for x in a.split("|"))]
    if missing:
        lines.append(f"\n(step anchors not called by the solver loop: {', '.join(missing)}; "
                     "those steps are merged with their neighbours: update PhaseTimer)")
    return "\n".join(lines)


def profile(what: str, iters: int, n: int = 15) -> str:
    import cProfile
    import io
    import pstats

    from meshrepair import denoise

    V, F = _load_for_profile(what)
    kw = _profile_kwargs(what, iters)
    denoise(V, F, **kw)  # warm-up
    pr = cProfile.Profile()
    t = time.perf_counter()
    pr.enable()
    res = denoise(V, F, **kw)
    pr.disable()
    dt = time.perf_counter() - t
    extra = f", {kw}" if kw else ""
    out = [f"cProfile of one default denoise, `{what}` ({len(V):,} vertices{extra}): "
           f"{res.iterations} iterations, {dt:.2f} s under the profiler"]
    for key in ("cumulative", "tottime"):
        s = io.StringIO()
        pstats.Stats(pr, stream=s).strip_dirs().sort_stats(key).print_stats(n)
        txt = s.getvalue()
        txt = txt[txt.find("   ncalls"):] if "   ncalls" in txt else txt
        out += [f"\nTop {n} by {key}:", "```", txt.rstrip(), "```"]
    return "\n".join(out)


def n_solver_table(args) -> str:
    """s/iter of the N-subproblem solvers (``n_solver="cg"`` vs ``"direct"``) on a few sizes."""
    half = args.iters // 2
    cases = [{"name": n, "kind": "pair", "noisy": a, "truth": b} for n, a, b in PAIRS
             if n.startswith(("fandisk γ0.3", "nicolo", "bunny"))]
    cases += [{"name": f"{args.scale_base} ×{lv} subdiv +γ{SCALE_GAMMA}", "kind": "scaling",
               "base": args.scale_base, "levels": lv, "gamma": SCALE_GAMMA, "seed": 0,
               "denoise_kwargs": {"robust_iters": half, "feature_iters": args.iters - half}}
              for lv in ([2] if args.quick else [2, 3])]
    rows = ["| case | nV | its | s/iter cg | s/iter direct | direct / cg | total s cg | "
            "total s direct | MSAE cg | MSAE direct |",
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for c in cases:
        if c["kind"] == "scaling":
            C.generate_subprocess(c["base"], c["levels"], c["gamma"], c["seed"])
        out = {}
        for ns in ("cg", "direct"):
            spec = dict(c, repeats=args.repeats, trace=False)
            spec["denoise_kwargs"] = {**c.get("denoise_kwargs", {}), "n_solver": ns}
            out[ns] = C.run_case_subprocess(spec)
            print(f"  {c['name']} n_solver={ns}: {out[ns].get('s_per_iter', out[ns].get('error'))}",
                  file=sys.stderr, flush=True)
        if any("error" in r for r in out.values()):
            rows.append(f"| {c['name']} | FAILED |")
            continue
        a, b = out["cg"], out["direct"]
        rows.append(f"| {c['name']} | {a['nV']:,} | {a['iterations']} | {a['s_per_iter']:.4f} | "
                    f"{b['s_per_iter']:.4f} | {b['s_per_iter'] / a['s_per_iter']:.2f} | "
                    f"{a['total_s']:.2f} | {b['total_s']:.2f} | {a['msae_out']:.2f} | "
                    f"{b['msae_out']:.2f} |")
    return "\n".join(rows)


# --------------------------------------------------------------------------------------------
# side by side with MeshLib meshDenoiseViaNormals (issue 15), and the targets
# --------------------------------------------------------------------------------------------

VS_CASES = [  # (name, base mesh, subdivision levels): noisy CAD parts, normal noise γ = 0.3
    ("twelve +γ0.3", "twelve", 0),
    ("screwdriver ×1 subdiv +γ0.3", "screwdriver", 1),
    ("screwdriver ×3 subdiv +γ0.3", "screwdriver", 3),
]
TARGETS = {"vs_ratio": 1.0, "full_1m_s": 30.0, "full_1m_rss_mb": 3000.0, "exponent": 1.05}


def _vs_worker(spec: dict) -> dict:
    import subprocess

    cmd = [sys.executable, str(Path(__file__).resolve().parent / "_vs_meshlib.py"), "--worker",
           json.dumps(spec)]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=str(C.ROOT))
    for line in p.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    return {"error": f"exit {p.returncode}: " + "\n".join(p.stderr.strip().splitlines()[-5:])}


def _med(rs: list[dict], k: str) -> float:
    return float(np.median([x[k] for x in rs]))


def _ratio(ml: list[dict], mr: list[dict], k: str, cold: bool = False) -> float:
    """Median over paired rounds of meshrepair / MeshLib (``cold``: import included)."""
    def v(x):
        return x[k] + (x["import_s"] if cold else 0.0)
    return float(np.median([v(b) / v(a) for a, b in zip(ml, mr, strict=True)]))


def vs_meshlib(args) -> list[dict]:
    """Each case: MeshLib and meshrepair in turn (A B A B ...), each in a fresh process,
    ``--vs-rounds`` times; per figure the median, and the median of the per-round ratios. One
    untimed meshrepair run first fills numba's disk cache, so that "first call" means loading
    the compiled kernels (as after any earlier use), not compiling them after an install."""
    rows = []
    for name, base, lv in VS_CASES:
        if args.only and not re.search(args.only, name, re.I):
            continue
        C.generate_subprocess(base, lv, SCALE_GAMMA)
        npz = str(C.CACHE / f"{base}_sub{lv}_g{SCALE_GAMMA:g}_s0.npz")
        warm = 3 if lv <= 1 else 1
        runs: dict[str, list[dict]] = {"meshlib": [], "meshrepair": []}
        if not vs_meshlib.warmed:  # fill numba's disk cache (a fresh copy compiles once)
            _vs_worker({"lib": "meshrepair", "npz": npz, "warm": 0})
            vs_meshlib.warmed = True
        for _ in range(args.vs_rounds):
            for lib in ("meshlib", "meshrepair"):
                r = _vs_worker({"lib": lib, "npz": npz, "warm": warm})
                if "error" in r:
                    raise SystemExit(f"{name} {lib}: {r['error']}")
                runs[lib].append(r)
                print(f"  {name} {lib}: import {r['import_s']:.2f} first {r['first_s']:.3f} "
                      f"warm {r['warm_s']:.3f} msae {r['msae_out']:.2f}", file=sys.stderr,
                      flush=True)
        ml, mr = runs["meshlib"], runs["meshrepair"]

        rows.append({"name": name, "nV": mr[0]["nV"], "rounds": args.vs_rounds, "warm_calls": warm,
                     "ml_import": _med(ml, "import_s"), "ml_first": _med(ml, "first_s"),
                     "ml_warm": _med(ml, "warm_s"), "mr_import": _med(mr, "import_s"),
                     "mr_first": _med(mr, "first_s"), "mr_warm": _med(mr, "warm_s"),
                     "ratio_first": _ratio(ml, mr, "first_s"),
                     "ratio_warm": _ratio(ml, mr, "warm_s"),
                     "ratio_cold": _ratio(ml, mr, "first_s", cold=True),
                     "ml_msae": ml[0]["msae_out"], "mr_msae": mr[0]["msae_out"],
                     "msae_in": mr[0]["msae_in"], "runs": runs})
    return rows


vs_meshlib.warmed = False


def _before_msae(path: Path | None) -> dict[str, float]:
    """``name -> meshrepair MSAE`` from the ``--json`` of an earlier run (e.g. the code before
    this work, run from a frozen copy)."""
    if path is None:
        return {}
    d = json.loads(path.read_text())
    out = {r["name"]: r["msae_out"] for r in d.get("results", []) if "msae_out" in r}
    out.update({r["name"]: r["mr_msae"] for r in d.get("vs_meshlib", [])})
    return out


def vs_markdown(rows: list[dict], before: dict[str, float]) -> str:
    out = ["| case | nV | MeshLib first / warm s | meshrepair first / warm s | ratio first | "
           "ratio warm | import + first call s (MeshLib / meshrepair, ratio) | MSAE noisy | "
           "MSAE MeshLib | MSAE meshrepair | MSAE meshrepair before |",
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        b = before.get(r["name"])
        out.append(
            f"| {r['name']} | {r['nV']:,} | {r['ml_first']:.3f} / {r['ml_warm']:.3f} | "
            f"{r['mr_first']:.3f} / {r['mr_warm']:.3f} | **{r['ratio_first']:.2f}** | "
            f"**{r['ratio_warm']:.2f}** | {r['ml_import'] + r['ml_first']:.2f} / "
            f"{r['mr_import'] + r['mr_first']:.2f}, {r['ratio_cold']:.2f} | {r['msae_in']:.1f} | "
            f"{r['ml_msae']:.2f} | {r['mr_msae']:.2f} | {_f(b)} |")
    if rows:
        out.append(f"\nratio = meshrepair / MeshLib time, median of {rows[0]['rounds']} paired "
                   "rounds (each library in a fresh process per round: first call after the "
                   "import, then the minimum of the warm calls); import = the library's own "
                   "`import`.")
    return "\n".join(out)


def msae_guard_markdown(results: list[dict], before: dict[str, float], tol: float = 0.02) -> str:
    """MSAE now vs before for every row of the table/scaling runs; rows worse by more than tol."""
    pairs = [(r["name"], before[r["name"]], r["msae_out"]) for r in results
             if "msae_out" in r and r["name"] in before]
    if not pairs:
        return ""
    worse = [f"{n} ({b:.2f} → {a:.2f})" for n, b, a in pairs if a > (1 + tol) * b]
    d = [100 * (a / b - 1) for _, b, a in pairs]
    return (f"MSAE against the earlier run: {len(pairs)} rows, change {min(d):+.2f} % to "
            f"{max(d):+.2f} % (median {np.median(d):+.2f} %); rows worse by more than "
            f"{100 * tol:.0f} %: {', '.join(worse) if worse else 'none'}.")


def targets_markdown(vs_rows: list[dict], srows: list[dict], iters_cap: int) -> str:
    """The targets of issue 15 that this run measured, each with its figure and met / missed."""
    lines = ["| target | asked | measured | status |", "|---|---|---|---|"]

    def st(ok):
        return "**met**" if ok else "**missed**"

    for r in vs_rows:
        for k, lab in (("ratio_first", "first call"), ("ratio_warm", "warm call")):
            ok = r[k] <= TARGETS["vs_ratio"]
            lines.append(f"| time / MeshLib, {r['name']} ({r['nV']:,} V), {lab} | ≤ "
                         f"{TARGETS['vs_ratio']:g} | {r[k]:.2f} | {st(ok)} |")
    full = [r for r in srows if "error" not in r and not r.get("denoise_kwargs")
            and 1_000_000 <= r["nV"] < 2_000_000]
    for r in full:
        lines.append(f"| full default run, {r['nV']:,} V | < {TARGETS['full_1m_s']:g} s | "
                     f"{r['total_s']:.1f} s ({r['iterations']} its) | "
                     f"{st(r['total_s'] < TARGETS['full_1m_s'])} |")
        lines.append(f"| peak RSS of that process | < {TARGETS['full_1m_rss_mb']:g} MB | "
                     f"{r['rss_peak_mb']:.0f} MB | "
                     f"{st(r['rss_peak_mb'] < TARGETS['full_1m_rss_mb'])} |")
    good = [r for r in srows if "error" not in r]
    if len(good) >= 3:
        n = np.array([r["nV"] for r in good], float)
        k = float(np.polyfit(np.log(n), np.log([r["s_per_iter"] for r in good]), 1)[0])
        lines.append(f"| growth exponent of s/iter ({int(n.min()):,}–{int(n.max()):,} V) | ≤ "
                     f"{TARGETS['exponent']:g} | {k:.3f} | {st(k <= TARGETS['exponent'])} |")
    return "\n".join(lines) if len(lines) > 2 else ""


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true",
                    help="skip the scaling rows of 295k vertices and more")
    ap.add_argument("--big", action="store_true", help="add the ~4.7M-vertex scaling row")
    ap.add_argument("--out", type=Path, help="write the markdown tables to this file")
    ap.add_argument("--json", type=Path, help="write the raw results (JSON) to this file")
    ap.add_argument("--repeats", type=int, default=3,
                    help="timed runs per case, minimum reported (default 3)")
    ap.add_argument("--repeats-big", type=int, default=1,
                    help="timed runs for scaling rows of 1M+ vertices (default 1)")
    ap.add_argument("--iters", type=int, default=20,
                    help="ADMM iteration cap of the scaling rows (default 20; 0: no cap, the "
                         "full default schedule is measured)")
    ap.add_argument("--scale-base", default="twelve",
                    help="shared mesh subdivided for the scaling rows (default twelve)")
    ap.add_argument("--scale-levels", help="comma-separated subdivision levels, e.g. 1,2,3,4")
    ap.add_argument("--only", help="regex: run only the cases whose name matches")
    ap.add_argument("--no-scaling", action="store_true", help="skip the scaling rows")
    ap.add_argument("--no-table", action="store_true", help="only the scaling rows")
    ap.add_argument("--no-trace", action="store_true", help="skip the tracemalloc runs")
    ap.add_argument("--profile", nargs="?", const="noisy/fandisk__gauss0.3", metavar="MESH",
                    help="cProfile + per-step breakdown of one default denoise instead of the "
                         "table (MESH: shared mesh name, or scale:BASE:LEVELS)")
    ap.add_argument("--n-solver-table", action="store_true",
                    help="compare n_solver='cg' and 'direct' (s/iter) instead of the table")
    ap.add_argument("--vs-meshlib", action="store_true",
                    help="time meshrepair against MeshLib meshDenoiseViaNormals (defaults) side "
                         "by side at ~5k, 13.6k and 217k vertices, first call and warm")
    ap.add_argument("--vs-rounds", type=int, default=3,
                    help="paired rounds per --vs-meshlib case (default 3)")
    ap.add_argument("--before", type=Path, metavar="JSON",
                    help="the --json of an earlier run: print its MSAE beside this run's")
    ap.add_argument("--run-one", metavar="MESH",
                    help="run one default denoise in process (for python -m cProfile)")
    args = ap.parse_args(argv)

    info = C.machine_info()
    if args.run_one:
        C.limit_threads(1)
        from meshrepair import denoise

        V, F = _load_for_profile(args.run_one)
        t = time.perf_counter()
        r = denoise(V, F, **_profile_kwargs(args.run_one, args.iters))
        print(f"{args.run_one}: {len(V)} vertices, {r.iterations} iterations, "
              f"{time.perf_counter() - t:.2f} s", file=sys.stderr)
        return 0
    if args.profile:
        C.limit_threads(1)
        C.warm_imports()
        txt = (f"Machine: {info}\n\n" + profile(args.profile, args.iters) + "\n\n"
               + breakdown(args.profile, args.iters))
        print(txt)
        if args.out:
            args.out.write_text(txt + "\n")
        return 0

    if args.n_solver_table:
        txt = (f"Machine: {info}\n\n" + n_solver_table(args))
        print(txt)
        if args.out:
            args.out.write_text(txt + "\n")
        return 0
    table, scaling = build_cases(args)
    if args.vs_meshlib and not args.only:
        table, scaling = [], []  # --vs-meshlib alone: only the side-by-side rows
    print(f"# machine: {info}", file=sys.stderr)
    results = []
    t_all = time.perf_counter()
    vs_rows = vs_meshlib(args) if args.vs_meshlib else []
    for c in table + scaling:
        if c["kind"] == "scaling":
            C.generate_subprocess(c["base"], c["levels"], c["gamma"], c["seed"])
        t = time.perf_counter()
        r = C.run_case_subprocess(c)
        r["wall_s"] = time.perf_counter() - t
        results.append(r)
        if "error" in r:
            print(f"  {c['name']}: FAILED {r['error']}", file=sys.stderr)
        else:
            print(f"  {c['name']}: nV={r['nV']} its={r['iterations']} total={r['total_s']:.2f}s "
                  f"s/it={r['s_per_iter']:.4f} msae {r['msae_in']:.1f}->{r['msae_out']:.2f} "
                  f"rssΔ={r['rss_delta_mb']:.0f}MB "
                  f"trace={r.get('trace_peak_mb', float('nan')):.0f}MB "
                  f"[{r['wall_s']:.0f}s wall]", file=sys.stderr, flush=True)
    info_end = C.machine_info()
    md = [f"Machine: {info.get('cpu', '?')}, {info.get('cores')} cores, {info.get('ram_gb')} GB "
          f"RAM; Python {info['python']}, numpy {info['numpy']}, scipy {info.get('scipy')}, "
          f"numba {info.get('numba')}; repo at git {info.get('git')}, package "
          f"`{info.get('pkg')}`; "
          f"BLAS limited to 1 thread; load average at start {info.get('loadavg')}, at end "
          f"{info_end.get('loadavg')}; memory probe {info.get('memprobe_ms')} ms at start, "
          f"{info_end.get('memprobe_ms')} ms at end; "
          f"benchmark wall time {time.perf_counter() - t_all:.0f} s; "
          f"{time.strftime('%Y-%m-%d %H:%M')}.", ""]
    rows = [r for r in results if r["kind"] != "scaling"]
    srows = [r for r in results if r["kind"] == "scaling"]
    before = _before_msae(args.before)
    if rows:
        md += [f"Default `denoise(V, F)`; min of {args.repeats} runs per case.", "",
               table_markdown(rows, before), ""]
    if srows:
        md += ["Scaling (subdivided shared mesh + normal noise γ = 0.3, seed 0):", "",
               scaling_markdown(srows, args.iters), ""]
    if vs_rows:
        md += ["Side by side with MeshLib `meshDenoiseViaNormals` (default settings):", "",
               vs_markdown(vs_rows, before), ""]
    guard = msae_guard_markdown(results, before)
    if guard:
        md += [guard, ""]
    tg = targets_markdown(vs_rows, srows, args.iters)
    if tg:
        md += ["Targets (issue 15) measured in this run:", "", tg, ""]
    states = sorted({r["pkg"].split("@")[-1][:10] for r in results if r.get("pkg")})
    if len(states) > 1:
        md.append(f"**Warning**: the package changed during the run ({states}); rows are not "
                  "comparable. Re-run, e.g. against a frozen copy: `cp -r src /tmp/snap && "
                  "PYTHONPATH=/tmp/snap python benchmarks/denoise.py`.")
    text = "\n".join(md)
    print(text)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + "\n")
    if args.json:
        args.json.write_text(json.dumps({"machine": info, "results": results,
                                         "vs_meshlib": vs_rows}, indent=1))
    return 1 if any("error" in r for r in results) else 0


if __name__ == "__main__":
    sys.exit(main())
