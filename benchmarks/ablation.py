"""Ablation of the denoiser's ingredients: what each stage and gate buys on the benchmark grid.

Usage::

    python benchmarks/ablation.py [--quick] [--only SUBSTR] [--json rows.json] [--out table.md]
    python benchmarks/ablation.py --table rows.json     # the markdown of a saved run

Rows are the whole grid of ``benchmarks/holdout.py`` (its ``CASES``, loaded by its ``load`` and
split by its ``DESIGN`` set into *design* and *check*), eight rows of
``benchmarks/whiteness.py`` (:data:`WHITENESS`, split by that script's ``DESIGN`` / ``CHECK``:
the grid of holdout.py has no input that reads correlated but is white, so the white-noise test
would not be ablated), and the published triples of ``shared/meshes/published``
(``benchmarks/published.py``'s ``cases``), a third group (two of them, ``gcn_trim_star_n3`` and
``tgv_kinect_pyramid``, are the inputs of holdout's ``trim_star n3`` and
``kinect_pyramid (real)``). The meshes are small (3k-35k vertices); the full run takes about
30 minutes on one core. Not on this grid: finer meshes (``benchmarks/resolution.py``), for
which the resolution gates of ``scalefree.py`` and ``coarse_lowpass.py`` are written.

Each column is one ingredient switched off, everything else at its default:

* *plan edits*: ``mr.plan_denoise(V, F)`` once per row, then ``mr.denoise(V, F, plan=...)``
  with the edit applied to the plan and to every plan it may run (``inner``, the plan of the
  low-passed input, and ``if_correlated``). An edit that leaves every plan as it was (the
  ingredient is not in this row's plan) prints ``=`` and is not run;
* *switches*: a module constant ``NAME = True`` set to False (in every module of
  ``meshrepair.denoise`` that holds it, so names imported by value follow) for a plain
  ``mr.denoise(V, F)``, restored afterwards. Finishing steps first (they run after the main
  solve), then the gates of the reading (they change the plan).

Entries are MSAE(ingredient off) / MSAE(default) (``--metric ev``: the same with E_V, both are
recorded): above 1 the ingredient pays on that row, below 1 it costs; ``·`` marks a run whose
result is identical to the default's. The summary gives per split the rows where the result
changed (``n``), the median ratio over those rows, and the rows worse (> 1.05) / better
(< 0.95) without the ingredient.
"""

from __future__ import annotations

import argparse
import importlib
import json
import pkgutil
import statistics
import sys
import time
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402, I001  (sets the thread env vars before numpy is imported)
import numpy as np  # noqa: E402

import holdout as H  # noqa: E402
import published as P  # noqa: E402
import whiteness as W  # noqa: E402


@dataclass(frozen=True)
class Ingredient:
    """One column: ``edit`` (plan -> plan) or ``switch`` (a module constant set to False)."""

    key: str
    what: str
    group: str
    edit: object = None
    switch: str | None = None


def _edit_all(plan, **kw):
    """``kw`` replaced in ``plan`` and in every plan it may run; ``(plan, changed)``."""
    if plan is None:
        return None, False
    inner, ci = _edit_all(plan.inner, **kw)
    corr, cc = _edit_all(plan.if_correlated, **kw)
    changed = ci or cc or any(getattr(plan, k) != v for k, v in kw.items())
    return replace(plan, inner=inner, if_correlated=corr, **kw), changed


def _edit_stages(plan, f):
    """``stages = f(stages)`` in ``plan`` and in every plan it may run; ``(plan, changed)``."""
    if plan is None:
        return None, False
    inner, ci = _edit_stages(plan.inner, f)
    corr, cc = _edit_stages(plan.if_correlated, f)
    st = tuple(f(plan.stages))
    return (replace(plan, inner=inner, if_correlated=corr, stages=st),
            ci or cc or st != plan.stages)


def _set(**kw):
    return lambda p: _edit_all(p, **kw)


def _no_presmooth(p):
    return (replace(p, presmooth_steps=0, inner=None), True) if p.presmooth_steps else (p, False)


def _white_only(p):
    if p.if_correlated is not None:
        return replace(p, if_correlated=None), True
    if p.inner is not None and p.inner.if_correlated is not None:
        return replace(p, inner=replace(p.inner, if_correlated=None)), True
    return p, False


def _correlated_only(p):
    if p.if_correlated is not None:
        return p.if_correlated, True
    if p.inner is not None and p.inner.if_correlated is not None:
        return replace(p, inner=p.inner.if_correlated), True
    return p, False


def _cad_only(p):
    if p.if_structured is not None:
        return replace(p, if_structured=None), True
    return p, False


def _no_robust(p):
    return _edit_stages(p, lambda s: [x for x in s if x.name != "robust"])


def _no_flat_tv(p):
    return _edit_stages(p, lambda s: [replace(x, flat_a=0.0) for x in s])


def _inner3(p):
    return _edit_all(p, inner_iters=3)


PLAN, FINISH, READ = "plan edit", "finishing switch", "reading switch"
INGREDIENTS = [
    Ingredient("coarse-to-fine", "presmooth_steps=0: no Taubin low-pass of the input before the "
               "schedule (heavy white noise on organic meshes)", PLAN, _no_presmooth),
    Ingredient("corr. model", "if_correlated=None: the white model's result is kept even when "
               "its residual fails the white-noise test", PLAN, _white_only),
    Ingredient("white model", "the correlated model's plan alone (plan.if_correlated), without "
               "the white model's run and its test", PLAN, _correlated_only),
    Ingredient("structure test", "if_structured=None: a CAD part's result is kept even when "
               "its residual holds structure (the organic plan not tried)", PLAN, _cad_only),
    Ingredient("w", "willmore_weight=1: no edge-Willmore weight read from the noise's correlation",
               PLAN, _set(willmore_weight=1.0)),
    Ingredient("V-steps", "inner_iters=3: no extra V-steps for correlated noise", PLAN, _inner3),
    Ingredient("w_out", "outside_weight=1: no stronger edge-Willmore off the creases of CAD parts",
               PLAN, _set(outside_weight=1.0)),
    Ingredient("Huber", "huber_delta=0: quadratic fidelity for impulsive noise", PLAN,
               _set(huber_delta=0.0)),
    Ingredient("warm start", "start_from_probe=False: the main solve starts from the input",
               PLAN, _set(start_from_probe=False)),
    Ingredient("robust stage", "the main solve without its robust (MC, a = 0.5) stage", PLAN,
               _no_robust),
    Ingredient("flat-TV", "flat_a=0: edge-Willmore instead of the flat-TV class on C's flat "
               "edges", PLAN, _no_flat_tv),
    Ingredient("polish flag", "polish=False: neither the polish nor the crease sharpening",
               PLAN, _set(polish=False)),
    Ingredient("polish", "rules.POLISH: the crease-bounded polish (heavy noise on CAD parts, "
               "correlated noise)", FINISH, switch="POLISH"),
    Ingredient("polish data", "finish.POLISH_DATA: the polish's data term", FINISH,
               switch="POLISH_DATA"),
    Ingredient("low-pass", "lowpass.LOWPASS: Taubin low-pass of the smooth region of organic "
               "meshes", FINISH, switch="LOWPASS"),
    Ingredient("re-anchor", "finish.REANCHOR: tangential re-anchoring of the smooth region",
               FINISH, switch="REANCHOR"),
    Ingredient("organic", "rules.ORGANIC: the organic one-ring guidance and re-integration",
               FINISH, switch="ORGANIC"),
    Ingredient("keep folds", "finish.REINTEGRATE_KEEPS_FOLDS: folds after a re-integration "
               "are unfolded", FINISH, switch="REINTEGRATE_KEEPS_FOLDS"),
    Ingredient("coarse", "coarse.COARSE: longer low-pass where the result is smooth at the "
               "mesh's resolution", FINISH, switch="COARSE"),
    Ingredient("CAD finish", "cadfinish.CAD_FINISH: one-ring guidance on CAD parts", FINISH,
               switch="CAD_FINISH"),
    Ingredient("sharpen", "rules.SHARPEN: crease sharpening for correlated noise", FINISH,
               switch="SHARPEN"),
    Ingredient("sharpen flat", "rules.SHARPEN_FLAT_SUPPORT: the sharpening's flat-support "
               "test", FINISH, switch="SHARPEN_FLAT_SUPPORT"),
    Ingredient("corr. low-pass", "corrlowpass.CORR_LOWPASS: the correlated-noise low-pass "
               "(both branches)", FINISH, switch="CORR_LOWPASS"),
    Ingredient("corr. white", "corrlowpass.CORR_WHITE: its branch 2 (correlated noise that "
               "reads white)", FINISH, switch="CORR_WHITE"),
    Ingredient("discrepancy", "discrepancy.DISCREPANCY: the residual check of w_out", FINISH,
               switch="DISCREPANCY"),
    Ingredient("unfold result", "folds.UNFOLD_RESULT: faces folded in the result stay folded",
               FINISH, switch="UNFOLD_RESULT"),
    Ingredient("organic λ", "organic_fidelity.ORGANIC_FIDELITY: the organic data weight law",
               READ, switch="ORGANIC_FIDELITY"),
    Ingredient("noise network", "crease_network.NOISE_NETWORK: noise chains kept as creases",
               READ, switch="NOISE_NETWORK"),
    Ingredient("heavy network", "crease_network.HEAVY_FROM_NETWORK: dropped chains do not mark "
               "heavy noise", READ, switch="HEAVY_FROM_NETWORK"),
    Ingredient("heavy length", "heavylength.HEAVY_LENGTH: the coarse-to-fine length not read "
               "from the relief", READ, switch="HEAVY_LENGTH"),
    Ingredient("coarse cap", "coarse_lowpass.COARSE_CAP: the coarse-to-fine length not capped "
               "at the resolution", READ, switch="COARSE_CAP"),
    Ingredient("keep white", "coarse_lowpass.KEEP_WHITE: a capped low-pass does not keep the "
               "white read", READ, switch="KEEP_WHITE"),
    Ingredient("layout keep", "layoutkeep.LAYOUT_KEEP: low-passes do not resample at the "
               "input's layout", READ, switch="LAYOUT_KEEP"),
    Ingredient("c2f layout keep", "layoutkeep.PRESMOOTH_KEEP: the coarse-to-fine low-pass does "
               "not resample at the input's layout", READ, switch="PRESMOOTH_KEEP"),
    Ingredient("unfold data", "folds.UNFOLD_DATA_IMPULSIVE: the input, not the unfolded mesh, "
               "is the data of impulsive noise", READ, switch="UNFOLD_DATA_IMPULSIVE"),
    Ingredient("probe stop", "rules.PROBE_EARLY_STOP: the probe runs to its cap", READ,
               switch="PROBE_EARLY_STOP"),
    Ingredient("scale-free stop", "scalefree.SCALE_FREE_STOP: the probe's tolerance not in "
               "edge units", READ, switch="SCALE_FREE_STOP"),
    Ingredient("gated stop", "scalefree.GATED_STOP: the scale-free stop also where the probe "
               "at the relative stop reads no crease", READ, switch="GATED_STOP"),
    Ingredient("scale-free CAD", "scalefree.SCALE_FREE_CAD: the CAD-part test not corrected "
               "for resolution", READ, switch="SCALE_FREE_CAD"),
]

WHITENESS = ["w:trim_star:0.1", "w:trim_star:0.2", "c:fandisk:0.4:3", "c:twelve:0.4:3",
             "w:trim_star:0.1:2", "w:spot:0.1:2", "c:spot:0.4:3", "c:trim_star:0.3:3"]
"""Rows of ``benchmarks/whiteness.py`` (the inputs that read as correlated noise, where the
white and the correlated models both run), with that script's design / check split; the
bunny rows (35k vertices, two models) are left out for time."""

QUICK = ["fandisk γ0.3 (published)", "twelve impulsive 0.5", "kinect_pyramid (real)",
         "spot γ0.4 normal", "rocker_arm γ0.3 normal", "camelhead correlated m=8 γ0.6",
         "w:trim_star:0.1", "nllr_pierrot"]


def _modules():
    """Every module of ``meshrepair.denoise``, imported (so that a switch is found wherever a
    module imported it by value)."""
    pkg = importlib.import_module("meshrepair.denoise")  # the package (``meshrepair.denoise``
    # as an attribute is the function)
    return [importlib.import_module(f"meshrepair.denoise.{m.name}")
            for m in pkgutil.iter_modules(pkg.__path__)]


@contextmanager
def switched_off(name: str):
    """``name = False`` in every module of :mod:`meshrepair.denoise` holding it (restored)."""
    held = [m for m in _modules() if getattr(m, name, None) is True]
    if not held:
        raise SystemExit(f"no module of meshrepair.denoise holds the switch {name} = True")
    try:
        for m in held:
            setattr(m, name, False)
        yield
    finally:
        for m in held:
            setattr(m, name, True)


def cases(quick: bool, only: str | None):
    """``(name, split, loader)`` rows: holdout's grid, whiteness's rows, the published
    triples."""
    out = [(c[1], "design" if c[1] in H.DESIGN else "check", lambda c=c: H.load(c))
           for c in H.CASES]

    def wh(c):
        Vt, Y, F = W._inputs(c)
        return Y, Vt, F

    for c in WHITENESS:
        split = "design" if c in W.DESIGN else "check" if c in W.CHECK else None
        if split is None:
            raise SystemExit(f"{c} is in neither split of benchmarks/whiteness.py")
        out.append((c, split, lambda c=c: wh(c)))

    def pub(n):
        from meshrepair import read_mesh

        t = read_mesh(P.PUBLISHED / f"{n}__truth.ply")
        return read_mesh(P.PUBLISHED / f"{n}__noisy.ply").V, t.V, t.F

    out += [(n, "published", lambda n=n: pub(n)) for n in P.cases()]
    if quick:
        out = [c for c in out if c[0] in QUICK]
    if only:
        out = [c for c in out if only in c[0]]
    return out


def run_row(name, split, loader, ingredients) -> dict:
    import meshrepair as mr
    from meshrepair import msae, vertex_error

    Vn, Vt, F = loader()
    t0 = time.perf_counter()
    plan = mr.plan_denoise(Vn, F)
    V0 = mr.denoise(Vn, F, plan=plan).V
    base = msae(V0, Vt, F)
    row = {"case": name, "split": split, "nV": len(Vn), "msae_in": msae(Vn, Vt, F),
           "msae": base, "ev": vertex_error(V0, Vt), "off": {}}
    for ing in ingredients:
        if ing.edit is not None:
            p, changed = ing.edit(plan)
            if not changed:
                row["off"][ing.key] = None
                continue
            V = mr.denoise(Vn, F, plan=p).V
        else:
            with switched_off(ing.switch):
                V = mr.denoise(Vn, F).V
        row["off"][ing.key] = {"msae": msae(V, Vt, F), "ev": vertex_error(V, Vt),
                               "same": bool(np.array_equal(V, V0))}
    row["time_s"] = time.perf_counter() - t0
    return row


METRIC = "msae"  # or "ev" (E_V, (34)): ``--metric``


def _label() -> str:
    return {"msae": "MSAE", "ev": "E_V"}[METRIC]


def ratio(row, key):
    """METRIC(off) / METRIC(default); None where the edit does not apply."""
    o = row["off"].get(key)
    if o is None:
        return None
    return 1.0 if o["same"] else o[METRIC] / row[METRIC]


def _cell(row, key):
    """``=`` not in the plan, ``·`` run with the result unchanged, else the ratio."""
    o = row["off"].get(key)
    if o is None:
        return "="
    return "·" if o["same"] else f"{o[METRIC] / row[METRIC]:.2f}"


def per_case_table(rows, ingredients) -> str:
    head = (f"| case | split | default {_label()} | " + " | ".join(i.key for i in ingredients)
            + " |")
    out = [head, "|---|---|---:|" + "---:|" * len(ingredients)]
    for r in rows:
        out.append(f"| {r['case']} | {r['split']} | {r[METRIC]:.4g} | "
                   + " | ".join(_cell(r, i.key) for i in ingredients) + " |")
    return "\n".join(out)


SPLITS = ("design", "check", "published")


def summary(rows, ingredients) -> list[dict]:
    """Per ingredient and split: rows where the result changed, their median ratio, and the
    rows worse (> 1.05) / better (< 0.95) without the ingredient."""
    out = []
    for i in ingredients:
        s = {"key": i.key, "group": i.group}
        for sp in SPLITS:
            rs = [ratio(r, i.key) for r in rows if r["split"] == sp]
            acts = [x for x in rs if x is not None and x != 1.0]
            s[sp] = {"rows": len(rs), "n": len(acts),
                     "median": statistics.median(acts) if acts else None,
                     "worse": sum(x > 1.05 for x in acts), "better": sum(x < 0.95 for x in acts)}
        out.append(s)
    return out


def summary_table(rows, ingredients) -> str:
    head = ("| ingredient switched off | " + " | ".join(
        f"{sp}: n | median | worse / better" for sp in SPLITS) + " |")
    out = [head, "|---|" + "---:|---:|---:|" * len(SPLITS)]
    for s in summary(rows, ingredients):
        cells = []
        for sp in SPLITS:
            d = s[sp]
            cells += ([f"0/{d['rows']}", "", ""] if not d["n"] else
                      [f"{d['n']}/{d['rows']}", f"{d['median']:.2f}",
                       f"{d['worse']} / {d['better']}"])
        out.append(f"| {s['key']} | " + " | ".join(cells) + " |")
    return "\n".join(out)


def markdown(rows, ingredients, machine: str) -> str:
    m = _label()
    parts = [machine, "", "Summary (per split: rows where the result changed / rows; median "
             f"ratio {m}(off) / {m}(default) over those rows; rows worse (> 1.05) and better "
             "(< 0.95) without the ingredient):", "", summary_table(rows, ingredients)]
    for g in (PLAN, FINISH, READ):
        sel = [i for i in ingredients if i.group == g]
        if sel:
            plural = g.replace("switch", "switche") + "s"
            parts += ["", f"Per case, {plural} ({m}(off) / {m}(default); = not in the "
                      "plan, · result unchanged):", "",
                      per_case_table(rows, sel)]
    return "\n".join(parts)


def machine_line(info: dict) -> str:
    return (f"machine: {info.get('cpu')}, {info.get('cores')} cores, load "
            f"{info.get('loadavg')}, memory probe {info['memprobe_ms']} ms, git {info['git']}, "
            f"pkg {info['pkg']}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help=f"only {len(QUICK)} rows: "
                    + ", ".join(QUICK))
    ap.add_argument("--only", help="substring of the case names to run")
    ap.add_argument("--columns", help="comma-separated ingredient keys (default: all)")
    ap.add_argument("--json", help="write the rows here")
    ap.add_argument("--out", help="write the markdown here")
    ap.add_argument("--table", metavar="JSON", help="print the markdown of a saved run and exit")
    ap.add_argument("--metric", choices=("msae", "ev"), default="msae",
                    help="the error the ratios compare: MSAE (33) or E_V (34)")
    args = ap.parse_args(argv)
    global METRIC
    METRIC = args.metric
    ings = INGREDIENTS
    if args.columns:
        keys = [k.strip() for k in args.columns.split(",")]
        ings = [i for i in INGREDIENTS if i.key in keys]
    if args.table:
        d = json.loads(Path(args.table).read_text())
        done = set(d["rows"][0]["off"]) if d["rows"] else set()
        print(markdown(d["rows"], [i for i in ings if i.key in done], machine_line(d["machine"])))
        return
    C.limit_threads(1)
    info = C.machine_info()
    print("# " + machine_line(info), flush=True)
    C.warm_imports()
    t0 = time.perf_counter()
    rows = []
    for name, split, loader in cases(args.quick, args.only):
        rows.append(run_row(name, split, loader, ings))
        r = rows[-1]
        print(f"{name} [{split}] default {r['msae']:.2f} ({r['time_s']:.0f} s): "
              + " ".join(f"{i.key} {_cell(r, i.key)}" for i in ings), flush=True)
    print(f"# {time.perf_counter() - t0:.0f} s", flush=True)
    md = markdown(rows, ings, machine_line(info))
    print()
    print(md)
    if args.json:
        C.write_text(args.json, json.dumps({"machine": info, "rows": rows}, ensure_ascii=False,
                                           indent=1))
    if args.out:
        C.write_text(args.out, md + "\n")


if __name__ == "__main__":
    main()
