"""Reproduce Fig. 4 (inner solvers on one V-subproblem (26)) and Fig. 5 (ADMM energy per
iteration) of the paper; writes docs/img/convergence_{inner,init,admm}.png and docs/convergence.md.

Usage (from the project root)::

    python benchmarks/convergence.py                 # everything (a few minutes)
    python benchmarks/convergence.py --quick         # 60 inner iterations, 2 ADMM meshes
    python benchmarks/convergence.py --k 50          # take the subproblem of ADMM iteration 50
    python benchmarks/convergence.py --no-doc --json /tmp/conv.json

(a) Inner solvers. ``twelve`` and ``fandisk`` get noise (32) with γ = 0.2 (``add_noise(seed=0)``)
and the default ``denoise`` runs until the V-subproblem of ADMM iteration ``--k``. That
subproblem is captured *exactly as the solver poses it* by spying on the ``run_inner`` call of
``meshrepair.model.solver`` (data ``V0``, weights ``λ M_V²``, ``z = ρ2 − β2 N`` in normalised units,
the warm start ``V^(k−1)`` and the current Armijo step), then the run stops. Each inner solver of
``meshrepair.model.inner.run_inner`` is run on a fresh copy of it for ``--inner-iters`` iterations:
``gd`` with a fixed step (α = the step plain Armijo settles at on this subproblem, and α/4),
``armijo`` (plain, and with the Jacobi preconditioning the ADMM uses by default when the
package has it), ``heavy_ball``, ``lbfgs`` and ``bfgs`` (only for meshes of at most
``--bfgs-max-vertices``
vertices: scipy's BFGS keeps a dense (3 nV)² inverse Hessian and updates it with two dense
matrix products per iteration). Energy and gradient norm are recorded at every gradient
evaluation. E* is the lowest energy found (including a long L-BFGS reference run); the relative
gap is (E − E*) / (E_start − E*).

(b) Initialisations: the ADMM's Armijo and ``heavy_ball`` from the warm start, from the noisy data
``V0`` and from the warm start plus Gaussian noise (σ = 0.2 mean edge lengths, seed 1).

(c) ADMM: energy (6) of ``history`` per iteration of the default ``denoise`` on fandisk, twelve,
nicolo and spot with γ = 0.2 normal noise, stage switches marked.

Timings use one BLAS thread; the per-solver time is the minimum of ``--repeats`` uninstrumented
runs.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402, I001  (sets the thread env vars before numpy is imported)
import numpy as np  # noqa: E402

ROOT = C.ROOT
INNER_MESHES = ["twelve", "fandisk"]
ADMM_MESHES = ["fandisk", "twelve", "nicolo", "spot"]
GAP_TOL = 1e-6
GAPS = (1e-2, 1e-4, GAP_TOL)
COLORS = {"gd α": "tab:gray", "gd α/4": "tab:brown", "armijo": "tab:blue",
          "armijo + Jacobi (ADMM default)": "tab:cyan",
          "heavy_ball": "tab:orange", "lbfgs": "tab:green", "bfgs": "tab:red"}


# --------------------------------------------------------------------------------------------
# capture one V-subproblem
# --------------------------------------------------------------------------------------------

def capture_subproblem(V, F, k: int) -> dict:
    """Run the default denoise until the V-subproblem of ADMM iteration ``k``; return it."""
    import dataclasses

    import meshrepair.model.solver.admm as S
    from meshrepair import denoise

    orig = S.run_inner
    box: dict = {}
    calls = [0]
    stages: list[str] = []

    def spy(name, prob, V, iters, state):
        calls[0] += 1
        if calls[0] == k:
            box.update(V0=np.array(prob.V0, copy=True), wfid=np.array(prob.wfid, copy=True),
                       z=np.array(prob.z, copy=True), V=np.array(V, copy=True),
                       step=float(state.step), state=dataclasses.replace(state),
                       solver=name, iters=iters,
                       F=np.array(prob.F, copy=True), nV=int(prob.nV),
                       free=None if getattr(prob, "free", None) is None else prob.free.copy())
            raise S.StopRequested
        return orig(name, prob, V, iters, state)

    S.run_inner = spy
    try:
        denoise(V, F, callback=lambda e: stages.append(e["stage"]))
    finally:
        S.run_inner = orig
    if not box:
        raise SystemExit(f"the run ended before ADMM iteration {k}")
    box["stage"] = stages[-1] if stages else "?"
    box["k"] = k
    return box


def make_problem(sub: dict):
    from meshrepair.model.inner import VSubproblem

    fixed = None if sub["free"] is None else ~sub["free"]
    p = VSubproblem(sub["F"], sub["nV"], fixed=fixed)
    p.set(sub["V0"], sub["wfid"], sub["z"])
    return p


def inner_state(sub: dict, kind: str, step: float | None = None):
    """An ``InnerState`` for a run: ``"solver"`` = a copy of the state the ADMM run had at the
    captured iteration (its step, and its preconditioning if the package has that option),
    ``"plain"`` = unpreconditioned gradient steps, ``"jacobi"`` = Jacobi-preconditioned Armijo."""
    import dataclasses

    from meshrepair.model.inner import InnerState

    fields = {f.name for f in dataclasses.fields(InnerState)}
    if kind == "solver":
        return dataclasses.replace(sub["state"])
    kw = {"step": step if step is not None else
          (1.0 if kind == "jacobi" else sub["plain_step"])}
    if "precondition" in fields:
        kw["precondition"] = kind == "jacobi"
    return InnerState(**kw)


def record_run(sub: dict, solver: str, V_start, iters: int, state) -> dict:
    """Run inner solver ``solver`` (a ``run_inner`` name) on a fresh copy of the subproblem from
    ``V_start`` with ``state``, recording energy and gradient norm at every gradient evaluation."""
    from meshrepair.model.inner import run_inner

    p = make_problem(sub)
    orig = p.energy_grad
    E, G, T = [], [], []
    step0 = float(state.step)
    t0 = time.perf_counter()

    def eg(V):
        e, g = orig(V)
        E.append(float(e))
        G.append(float(np.linalg.norm(g)))
        T.append(time.perf_counter() - t0)
        return e, g

    p.energy_grad = eg
    Vf = run_inner(solver, p, np.array(V_start, copy=True), iters, state)
    t_end = time.perf_counter() - t0
    e, g = orig(Vf)  # the returned iterate
    E.append(float(e))
    G.append(float(np.linalg.norm(g)))
    T.append(t_end)
    return {"E": np.array(E), "G": np.array(G), "T": np.array(T), "V": Vf,
            "n_energy": int(p.n_energy) - 1, "n_grad": int(p.n_grad) - 1,
            "step": step0, "final_step": float(state.step)}


def time_run(sub: dict, solver: str, V_start, iters: int, make_state, repeats: int) -> float:
    from meshrepair.model.inner import run_inner

    best = np.inf
    for _ in range(repeats):
        p = make_problem(sub)
        V = np.array(V_start, copy=True)
        st = make_state()
        t = time.perf_counter()
        run_inner(solver, p, V, iters, st)
        best = min(best, time.perf_counter() - t)
    return float(best)


def reference_energy(sub: dict, V_start, iters: int) -> tuple[float, np.ndarray]:
    """A long L-BFGS run from the warm start (the best-effort minimum of the subproblem)."""
    from meshrepair.model.inner import run_inner

    p = make_problem(sub)
    V = run_inner("lbfgs", p, np.array(V_start, copy=True), iters, inner_state(sub, "plain"))
    e, g = p.energy_grad(V)
    return float(e), V, float(np.linalg.norm(g)), int(p.n_grad) - 1


def area_ratio(V, F) -> float:
    """Smallest face area / median face area (near-degenerate triangles show up here)."""
    a = np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    return float(a.min() / np.median(a))


def dists(V, V_ref) -> tuple[float, float]:
    """(max, RMS) vertex distance in normalised units (mean edge lengths)."""
    if not np.all(np.isfinite(V)):
        return float("nan"), float("nan")
    d = np.linalg.norm(V - V_ref, axis=1)
    return float(d.max()), float(np.sqrt(np.mean(d**2)))


def iters_to_gap(E, E0, Estar, tol=GAP_TOL):
    gap = (np.asarray(E) - Estar) / max(E0 - Estar, 1e-300)
    hit = np.flatnonzero(gap <= tol)
    return int(hit[0]) if len(hit) else None


# --------------------------------------------------------------------------------------------
# experiments
# --------------------------------------------------------------------------------------------

def inner_experiment(mesh: str, args) -> dict:
    from meshrepair import add_noise

    V, F, _ = C.read(mesh)
    Vn = add_noise(V, F, args.gamma, seed=0)
    t = time.perf_counter()
    sub = capture_subproblem(Vn, F, args.k)
    pre = bool(getattr(sub["state"], "precondition", False))
    sub["plain_step"] = 1e-2 if pre else sub["step"]
    print(f"[{mesh}] captured V-subproblem of ADMM iteration {args.k} ({sub['stage']} stage, "
          f"{sub['solver']}, state {sub['state']}) in {time.perf_counter() - t:.1f} s",
          file=sys.stderr)
    Vw = sub["V"]
    it = args.inner_iters
    # (label, run_inner name, state factory); gd's fixed step comes from the plain Armijo run
    specs = [("armijo", "armijo", lambda: inner_state(sub, "plain"))]
    if pre:
        specs.append(("armijo + Jacobi (ADMM default)", "armijo",
                      lambda: inner_state(sub, "solver")))
    specs += [("heavy_ball", "heavy_ball", lambda: inner_state(sub, "plain")),
              ("lbfgs", "lbfgs", lambda: inner_state(sub, "plain"))]
    skipped = []
    if sub["nV"] <= args.bfgs_max_vertices:
        specs.append(("bfgs", "bfgs", lambda: inner_state(sub, "plain")))
    else:
        skipped.append("bfgs")
    runs = {}

    def go(label, name, make):
        r = record_run(sub, name, Vw, it, make())
        r["time"] = time_run(sub, name, Vw, it, make, args.repeats)
        runs[label] = r
        print(f"[{mesh}] {label}: E {r['E'][0]:.6f} -> {r['E'][-1]:.6f}, |g| {r['G'][0]:.3g} -> "
              f"{r['G'][-1]:.3g}, {r['time']:.3f} s", file=sys.stderr)

    go(*specs[0])
    alpha = runs["armijo"]["final_step"]  # the step plain Armijo settled at on this problem
    for f in args.gd_factors:
        lab = "gd α" if f == 1 else (f"gd α/{1 / f:g}" if f < 1 else f"gd α×{f:g}")
        go(lab, "gd", lambda f=f: inner_state(sub, "plain", step=alpha * f))
    for spec in specs[1:]:
        go(*spec)
    first = [k for k in runs if k.startswith("gd")]
    runs = {k: runs[k] for k in first + [k for k in runs if k not in first]}
    E_ref, V_ref, G_ref, n_ref = reference_energy(sub, Vw, args.ref_iters)
    # (b) initialisations, with the ADMM's own Armijo variant and heavy ball
    rng = np.random.default_rng(1)
    inits = {"warm start V^(k)": Vw, "noisy data V0": sub["V0"],
             "V^(k) + N(0, 0.2²)": Vw + rng.normal(0.0, 0.2, Vw.shape)}
    init_solvers = [("armijo + Jacobi" if pre else "armijo", "armijo", "solver"),
                    ("heavy_ball", "heavy_ball", "plain")]
    init_runs = {}
    for lab_s, name, kind in init_solvers:
        for lab, V0 in inits.items():
            init_runs[(lab_s, lab)] = record_run(sub, name, V0, it, inner_state(sub, kind))
    finite = [E_ref] + [r["E"].min() for r in runs.values() if np.all(np.isfinite(r["E"]))]
    finite += [r["E"].min() for r in init_runs.values()]
    Estar = float(np.nanmin(finite))
    return {"mesh": mesh, "nV": int(sub["nV"]), "sub": sub, "runs": runs, "skipped": skipped,
            "E_ref": E_ref, "V_ref": V_ref, "G_ref": G_ref, "n_ref": n_ref, "Estar": Estar,
            "init_runs": init_runs, "area_warm": area_ratio(Vw, sub["F"]), "alpha": alpha}


def admm_experiment(mesh: str, args) -> dict:
    from meshrepair import add_noise, denoise, msae

    V, F, _ = C.read(mesh)
    Vn = add_noise(V, F, args.gamma, seed=0)
    t = time.perf_counter()
    r = denoise(Vn, F)
    dt = time.perf_counter() - t
    h = r.history
    print(f"[admm {mesh}] {r.iterations} its ({r.stop_reason}), {dt:.1f} s", file=sys.stderr)
    return {"mesh": mesh, "nV": len(V), "energy": [e["energy"] for e in h],
            "stage": [e["stage"] for e in h], "rel_change": [e["rel_change"] for e in h],
            "iterations": r.iterations, "stop": r.stop_reason, "seconds": dt,
            "msae_in": msae(Vn, V, F), "msae_out": msae(r.V, V, F)}


# --------------------------------------------------------------------------------------------
# plots
# --------------------------------------------------------------------------------------------

def _gap(E, E0, Estar):
    return np.maximum((np.asarray(E) - Estar) / max(E0 - Estar, 1e-300), 1e-16)


def plot_inner(results, path: Path):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(3, len(results), figsize=(5.2 * len(results), 11), squeeze=False)
    for j, res in enumerate(results):
        E0 = res["runs"]["armijo"]["E"][0]
        for s, r in res["runs"].items():
            c = COLORS.get(s)
            lab = s if not s.startswith("gd") else f"{s} (fixed step {r['step']:.2g})"
            E, G = r["E"], r["G"]
            if s in ("lbfgs", "bfgs"):  # scipy's line-search trial points: show the best so far
                best = np.array([int(np.argmin(E[:i + 1])) for i in range(len(E))])
                E, G = E[best], G[best]
                lab += " (best point so far)"
            it = np.arange(len(E))
            ax[0, j].semilogy(it, _gap(E, E0, res["Estar"]), color=c, label=lab)
            ax[1, j].semilogy(it, G, color=c, label=lab)
            ax[2, j].semilogy(r["T"], _gap(E, E0, res["Estar"]), color=c, label=lab)
        ax[0, j].axhline(GAP_TOL, color="k", lw=0.6, ls=":")
        ax[2, j].axhline(GAP_TOL, color="k", lw=0.6, ls=":")
        ax[0, j].set_title(f"{res['mesh']} γ=0.2, V-subproblem of ADMM it. {res['sub']['k']} "
                           f"({res['sub']['stage']})", fontsize=9)
        ax[0, j].set_ylabel("(J_V − J*) / (J_V(V^(k)) − J*)")
        ax[1, j].set_ylabel("‖∇J_V‖")
        ax[2, j].set_ylabel("relative energy gap")
        ax[0, j].set_xlabel("iteration (gradient evaluations)")
        ax[1, j].set_xlabel("iteration (gradient evaluations)")
        ax[2, j].set_xlabel("seconds (1 thread, instrumented)")
        for a in ax[:, j]:
            a.grid(alpha=0.3)
    ax[0, 0].legend(fontsize=8)
    fig.suptitle("Fig. 4 (rows 1-2): inner solvers on one V-subproblem (26)", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_init(results, path: Path):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, len(results), figsize=(5.2 * len(results), 4.2), squeeze=False)
    ls = {"armijo": "-", "armijo + Jacobi": "-", "heavy_ball": "--"}
    cols = ["tab:blue", "tab:purple", "tab:olive"]
    for j, res in enumerate(results):
        Estar = res["Estar"]
        labs = list(dict.fromkeys(lab for _, lab in res["init_runs"]))
        for (s, lab), r in res["init_runs"].items():
            ax[0, j].semilogy(np.arange(len(r["E"])), np.maximum(r["E"] - Estar, 1e-12),
                              ls=ls[s], color=cols[labs.index(lab)], label=f"{s}, {lab}")
        ax[0, j].set_title(f"{res['mesh']} γ=0.2: three initialisations", fontsize=9)
        ax[0, j].set_xlabel("iteration (gradient evaluations)")
        ax[0, j].set_ylabel("J_V − J*  (J* = lowest energy found)")
        ax[0, j].grid(alpha=0.3)
    ax[0, 0].legend(fontsize=7)
    fig.suptitle("Fig. 4 (row 3): robustness to the initialisation", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_admm(results, path: Path):
    import matplotlib.pyplot as plt

    n = len(results)
    cols = 2 if n > 1 else 1
    rows = (n + cols - 1) // cols
    fig, ax = plt.subplots(rows, cols, figsize=(5.2 * cols, 3.8 * rows), squeeze=False)
    for i, res in enumerate(results):
        a = ax[i // cols, i % cols]
        E = np.asarray(res["energy"])
        it = np.arange(1, len(E) + 1)
        a.semilogy(it, E, color="tab:blue")
        st = res["stage"]
        for q in range(1, len(st)):
            if st[q] != st[q - 1]:
                a.axvline(q + 0.5, color="tab:red", ls="--", lw=1)
                a.text(q + 1, E.max(), f" → {st[q]}", color="tab:red", va="top", fontsize=8)
        a.set_title(f"{res['mesh']} ({res['nV']:,} V) γ=0.2: {res['iterations']} its, "
                    f"stop: {res['stop']}", fontsize=9)
        a.set_xlabel("ADMM iteration")
        a.set_ylabel("energy J (6)")
        a.grid(alpha=0.3)
    for i in range(n, rows * cols):
        ax[i // cols, i % cols].axis("off")
    fig.suptitle("Fig. 5: ADMM energy per iteration (default denoise)", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# --------------------------------------------------------------------------------------------
# tables / doc
# --------------------------------------------------------------------------------------------

def inner_table(results, iters) -> str:
    out = ["| mesh | solver | final J_V − J* | final ‖∇J_V‖ | seconds for "
           f"{iters} its | ms / iteration | energy / gradient evaluations | gap after "
           f"{results[0]['sub']['iters']} its (as in ADMM) | "
           + " | ".join(f"its to gap ≤ {g:g}" for g in GAPS)
           + " | ‖V − V_ref‖ max / RMS (mean edges) | min / median face area |",
           "|---|---|---:|---:|---:|---:|---:|---:|" + "---:|" * len(GAPS) + "---:|---:|"]
    for res in results:
        E0 = res["runs"]["armijo"]["E"][0]
        for s, r in res["runs"].items():
            Eb = np.minimum.accumulate(r["E"]) if s in ("lbfgs", "bfgs") else r["E"]
            ns = [iters_to_gap(Eb, E0, res["Estar"], g) for g in GAPS]
            q = min(res["sub"]["iters"], len(Eb) - 1)
            g_q = (Eb[q] - res["Estar"]) / max(E0 - res["Estar"], 1e-300)
            dm, dr = dists(r["V"], res["V_ref"])
            out.append(f"| {res['mesh']} | {s} | {r['E'][-1] - res['Estar']:.3e} | "
                       f"{r['G'][-1]:.2e} | {r['time']:.2f} | {1e3 * r['time'] / iters:.2f} | "
                       f"{r['n_energy']} / {r['n_grad']} | {g_q:.3f} | "
                       + " | ".join("—" if n is None else str(n) for n in ns)
                       + f" | {dm:.2e} / {dr:.2e} | {area_ratio(r['V'], res['sub']['F']):.2e} |")
        for s in res["skipped"]:
            out.append(f"| {res['mesh']} | {s} | skipped: dense (3·{res['nV']})² inverse Hessian |"
                       + " |" * (7 + len(GAPS)))
        out.append(f"| {res['mesh']} | reference L-BFGS (≤ {res['ref_iters']} its, stopped "
                   f"after {res['n_ref']} evaluations) | "
                   f"{res['E_ref'] - res['Estar']:.3e} | {res['G_ref']:.2e} |"
                   + " |" * (4 + len(GAPS))
                   + f" 0 | {area_ratio(res['V_ref'], res['sub']['F']):.2e} |")
    return "\n".join(out)


def init_table(results) -> str:
    out = ["| mesh | solver | initialisation | J_V start − J* | final J_V − J* | final ‖∇J_V‖ | "
           "‖V − V_ref‖ max / RMS (mean edges) | min / median face area |",
           "|---|---|---|---:|---:|---:|---:|---:|"]
    for res in results:
        for (s, lab), r in res["init_runs"].items():
            out.append(f"| {res['mesh']} | {s} | {lab} | {r['E'][0] - res['Estar']:.3e} | "
                       f"{r['E'][-1] - res['Estar']:.3e} | {r['G'][-1]:.2e} | "
                       "{:.2e} / {:.2e} | ".format(*dists(r["V"], res["V_ref"]))
                       + f"{area_ratio(r['V'], res['sub']['F']):.2e} |")
    return "\n".join(out)


def admm_table(results) -> str:
    out = ["| mesh | nV | iterations (stop) | stages | J first → last | last 10 its: max "
           "relative change of J | seconds | MSAE noisy → result (deg²) |",
           "|---|---:|---|---|---|---:|---:|---|"]
    for r in results:
        E = np.asarray(r["energy"])
        st = list(dict.fromkeys(r["stage"]))
        cnt = ", ".join(f"{s} {r['stage'].count(s)}" for s in st)
        tail = E[-10:]
        rc = float(np.max(np.abs(np.diff(tail)) / np.abs(tail[1:]))) if len(tail) > 1 else 0.0
        out.append(f"| {r['mesh']} | {r['nV']:,} | {r['iterations']} ({r['stop']}) | {cnt} | "
                   f"{E[0]:.4g} → {E[-1]:.4g} | {rc:.1e} | {r['seconds']:.1f} | "
                   f"{r['msae_in']:.1f} → {r['msae_out']:.2f} |")
    return "\n".join(out)


INTERP_START = "<!-- interpretation: kept when the script rewrites this file -->"
INTERP_END = "<!-- /interpretation -->"


def write_doc(path: Path, inner, admm, args, info, elapsed):
    old = path.read_text() if path.exists() else ""
    m = re.search(re.escape(INTERP_START) + r"(.*?)" + re.escape(INTERP_END), old, re.S)
    interp = m.group(1).strip() if m else "_(interpretation to be written after a run)_"
    k = args.k
    txt = f"""# Convergence of the inner solvers and of ADMM (paper Fig. 4 and Fig. 5)

Generated by `python benchmarks/convergence.py` (the interpretation section is hand-written and
kept when the script rewrites this file; re-read it after a re-run). Run of
{time.strftime('%Y-%m-%d %H:%M')}, package `{info.get('pkg')}` (repo HEAD `{info.get('git')}`),
{info.get('cpu')},
{info.get('cores')} cores shared with other jobs (load average {info.get('loadavg')}), one BLAS
thread, {elapsed:.0f} s in all.

Setup: `twelve` and `fandisk` with noise (32), γ = 0.2, normal direction
(`add_noise(V, F, 0.2, seed=0)`). The default `denoise` runs until the V-subproblem (26) of ADMM
iteration {k}; that subproblem is captured exactly as the solver poses it (spy on
`meshrepair.model.solver.run_inner`: data, fidelity weights, `z = ρ2 − β2 N`, the warm start `V^(k)`
(the ADMM iterate entering iteration {k}) and the inner solver's state, all in normalised units:
centred, divided by the mean edge length),
and every inner solver of `meshrepair.model.inner.run_inner` runs {args.inner_iters} iterations on a
fresh copy, from the warm start: plain Armijo GD, the Jacobi-preconditioned Armijo GD the ADMM
uses by default (when the package has it: its state, step and preconditioning, are copied from
the ADMM run), heavy ball with backtracking (27), scipy L-BFGS-B, and GD with a fixed step: α
(the step plain Armijo settled at on this subproblem) and α/4. `J*` is the lowest energy found
by any run, including a {args.ref_iters}-iteration L-BFGS reference run from the warm start
whose end point is `V_ref`. The "relative gap" is `(J_V − J*) / (J_V(V^(k)) − J*)`. Curves
are per *gradient evaluation* (for armijo / heavy_ball that is one iteration; backtracking adds
energy-only evaluations; for L-BFGS a few iterations take more than one evaluation, and its
curves show the best point found so far, since scipy's line-search trial points can have much
higher energy). Seconds are the minimum of {args.repeats} uninstrumented runs. "min / median
face area" flags near-degenerate triangles (the normal in (26) is undefined at zero area and the
gradient (28) grows like 1/area).

## Interpretation

{INTERP_START}
{interp}
{INTERP_END}

## (a) Inner solvers on one V-subproblem (Fig. 4, rows 1-2)

![energy gap, gradient norm and energy gap vs time per inner solver](img/convergence_inner.png)

{inner_table(inner, args.inner_iters)}

## (b) Robustness to the initialisation (Fig. 4, row 3)

The ADMM's Armijo GD and heavy ball from the warm start `V^(k)`, from the noisy data `V0` and from
`V^(k)` plus Gaussian noise (σ = 0.2 mean edge lengths, seed 1), {args.inner_iters} iterations.

![energy vs iteration for three initialisations](img/convergence_init.png)

{init_table(inner)}

## (c) ADMM energy per iteration (Fig. 5)

Default `denoise` on four meshes with γ = 0.2 normal noise (seed 0): energy (6) of each
`history` entry, stage switches dashed. The energy is evaluated with the current stage's `a` and
sharp-edge mask, so it jumps where the stage (and, every 3 feature-stage iterations, the mask)
changes.

![ADMM energy per iteration](img/convergence_admm.png)

{admm_table(admm)}
"""
    path.write_text(txt)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true",
                    help="60 inner iterations, ADMM plot on fandisk and twelve only")
    ap.add_argument("--k", type=int, default=10, help="ADMM iteration whose V-subproblem is "
                                                      "taken (default 10)")
    ap.add_argument("--gamma", type=float, default=0.2)
    ap.add_argument("--inner-iters", type=int, default=200)
    ap.add_argument("--ref-iters", type=int, default=3000,
                    help="iterations of the L-BFGS reference run (default 3000)")
    ap.add_argument("--repeats", type=int, default=2, help="timing repeats (min reported)")
    ap.add_argument("--bfgs-max-vertices", type=int, default=1500,
                    help="run scipy BFGS only on meshes up to this many vertices (default 1500)")
    ap.add_argument("--gd-factors", type=lambda x: [float(v) for v in x.split(",")],
                    default=[1.0, 0.25], help="fixed gd steps as multiples of the captured Armijo "
                                              "step (default 1,0.25)")
    ap.add_argument("--inner-meshes", default=",".join(INNER_MESHES))
    ap.add_argument("--admm-meshes", default=None)
    ap.add_argument("--img-dir", type=Path, default=ROOT / "docs" / "img")
    ap.add_argument("--doc", type=Path, default=ROOT / "docs" / "convergence.md")
    ap.add_argument("--no-doc", action="store_true", help="do not rewrite the markdown file")
    ap.add_argument("--json", type=Path, help="write the numbers (curves) to this JSON file")
    args = ap.parse_args(argv)
    if args.quick:
        args.inner_iters = min(args.inner_iters, 60)
        args.ref_iters = min(args.ref_iters, 500)
    admm_meshes = (args.admm_meshes.split(",") if args.admm_meshes else
                   (ADMM_MESHES[:2] if args.quick else ADMM_MESHES))

    import matplotlib

    matplotlib.use("Agg")
    C.limit_threads(1)
    C.warm_imports()
    info = C.machine_info()
    t_all = time.perf_counter()
    inner = []
    for m in args.inner_meshes.split(","):
        res = inner_experiment(m, args)
        res["ref_iters"] = args.ref_iters
        inner.append(res)
    admm = [admm_experiment(m, args) for m in admm_meshes]
    args.img_dir.mkdir(parents=True, exist_ok=True)
    plot_inner(inner, args.img_dir / "convergence_inner.png")
    plot_init(inner, args.img_dir / "convergence_init.png")
    plot_admm(admm, args.img_dir / "convergence_admm.png")
    elapsed = time.perf_counter() - t_all
    print(inner_table(inner, args.inner_iters))
    print()
    print(init_table(inner))
    print()
    print(admm_table(admm))
    if not args.no_doc:
        write_doc(args.doc, inner, admm, args, info, elapsed)
        print(f"\nwrote {args.doc} and {args.img_dir}/convergence_*.png", file=sys.stderr)
    if args.json:
        def curves(r):
            return {"E": r["E"].tolist(), "G": r["G"].tolist(), "T": r["T"].tolist()}

        args.json.write_text(json.dumps({
            "machine": info,
            "inner": [{"mesh": r["mesh"], "Estar": r["Estar"], "E_ref": r["E_ref"],
                       "step": r["sub"]["step"], "stage": r["sub"]["stage"],
                       "runs": {s: {**curves(x), "time": x["time"]} for s, x in r["runs"].items()},
                       "init": {f"{s} | {lab}": curves(x)
                                for (s, lab), x in r["init_runs"].items()}} for r in inner],
            "admm": admm}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
