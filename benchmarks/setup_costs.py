"""The set-up of one default ``denoise`` call, split by phase: everything before the main solve's
ADMM iterations (issue 26).

One ``mr.denoise(V, F)`` call runs with CPU timers (``time.process_time``) around the functions
of its reading and plan (:mod:`meshrepair.denoise.analysis`) and of its execution
(:mod:`meshrepair.denoise.execute`) up to the main solve's iterations; the call is stopped when
the main solve enters its iteration loop (``ADMMSolver._run``), so the main iterations never run.
Nested timed calls count for the outermost one; time between timed calls (option checks,
decisions, array copies of the reordering) is the row "rest of the reading / plan". The probe's
ADMM iterations (every ``ADMMSolver._run`` before the main solve, phase 1 and 2 of the gated
probe) are a row of their own, and the table gives the set-up with and without them.

A warm-up call on a small mesh of the same kind loads the compiled kernels first; each figure is
the median over ``--repeats`` calls in this process.

With ``--old SRC`` it runs ``--pairs`` pairs of fresh processes, one on the package at ``SRC``
(a frozen copy, e.g. of the previous commit) and one on this checkout, alternately, so both
columns see the same load; each column is then the median over its processes.

Usage::

    python benchmarks/setup_costs.py [--mesh twelve:4] [--repeats 3] [--json out.json]
    python benchmarks/setup_costs.py --old /tmp/snap --pairs 3 [--json both.json]
    python benchmarks/setup_costs.py --table before.json after.json   # side by side

Prints a markdown table and the machine line with the memory probe (benchmarks/_common.py).
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

PROBE_ITERS = "probe: ADMM iterations"
REST = "rest of the reading / plan (checks, decisions, copies)"

# (module, attribute, phase): the timed functions, in the order a call meets them
TIMED = (
    ("meshrepair.mesh.validate", "_check_mesh", "validation + topology (_check_mesh)"),
    ("meshrepair.denoise.analysis", "noise_statistics", "noise level γ̂, γ̂_rms"),
    ("meshrepair.model.relax", "locally_flipped_faces", "fold-over check + untangle"),
    ("meshrepair.denoise.folds", "locally_flipped_faces", "fold-over check + untangle"),
    ("meshrepair.denoise.folds", "untangle", "fold-over check + untangle"),
    ("meshrepair.mesh.reorder", "locality_order", "Morton order + reordered topology"),
    ("meshrepair.mesh.topology", "edge_topology", "Morton order + reordered topology"),
    ("meshrepair.mesh.topology", "permuted_topology", "Morton order + reordered topology"),
    ("meshrepair.denoise.analysis", "fidelity_data", "rest of the reading / plan (checks, "
     "decisions, copies)"),
    ("meshrepair.denoise.scalefree", "radius_in_edges", "mesh radius in edge lengths"),
    ("meshrepair.model.solver.admm", "ADMMSolver.__init__", "probe: solver set-up"),
    ("meshrepair.model.solver.admm", "ADMMSolver._start", "probe: solver set-up"),
    ("meshrepair.model.solver.admm", "ADMMSolver._run", PROBE_ITERS),
    ("meshrepair.denoise.crease_network", "supported", "probe reading: crease support"),
    ("meshrepair.denoise.analysis", "tangential_ratio", "probe reading: tangential ratio r_t"),
    ("meshrepair.denoise.analysis", "noise_scale", "probe reading: noise scale ρ, ℓ"),
    ("meshrepair.denoise.analysis", "flat_edges", "probe reading: flat edges"),
    ("meshrepair.denoise.scalefree", "cad_support", "probe reading: CAD support"),
    ("meshrepair.denoise.organic_fidelity", "applies", "probe reading: organic fidelity"),
    ("meshrepair.denoise.organic_fidelity", "main_lambda", "probe reading: organic fidelity"),
    ("meshrepair.denoise.analysis", "_plan_presmooth", "coarse-to-fine decision"),
    ("meshrepair.denoise.analysis", "mesh_key", "mesh digest (plan and execution)"),
    ("meshrepair.denoise.execute", "mesh_key", "mesh digest (plan and execution)"),
)
MAIN_INIT = "main solve: solver set-up"


class _Stop(Exception):
    """Raised when the main solve enters its iterations."""


class SetupTimer:
    """CPU timers around :data:`TIMED`; :meth:`run` returns the seconds per phase."""

    def __init__(self):
        self.acc: dict[str, float] = {}
        self.depth = 0
        self.main = False  # the execution has begun: solver set-up is the main solve's
        self._undo = []

    def _wrap(self, owner, attr, label):
        orig = owner.__dict__[attr] if isinstance(owner, type) else getattr(owner, attr)
        tm = self

        def wrapper(*a, **k):
            if attr == "_run" and tm.main:
                raise _Stop
            if tm.depth:
                return orig(*a, **k)
            lab = MAIN_INIT if (tm.main and label.startswith("probe: solver")) else label
            t = time.process_time()
            tm.depth += 1
            try:
                return orig(*a, **k)
            finally:
                tm.depth -= 1
                tm.acc[lab] = tm.acc.get(lab, 0.0) + time.process_time() - t

        setattr(owner, attr, wrapper)
        self._undo.append((owner, attr, orig))

    def install(self):
        import importlib

        for mod, name, label in TIMED:
            owner = importlib.import_module(mod)
            if "." in name:
                cls, name = name.split(".")
                owner = getattr(owner, cls)
            if hasattr(owner, name):  # (a function an older package does not have)
                self._wrap(owner, name, label)
        run = importlib.import_module("meshrepair.denoise.run")
        orig_exec = run._execute
        tm = self

        def execute(*a, **k):
            tm.main = True
            return orig_exec(*a, **k)

        run._execute = execute
        self._undo.append((run, "_execute", orig_exec))

    def uninstall(self):
        for owner, attr, orig in reversed(self._undo):
            setattr(owner, attr, orig)
        self._undo.clear()

    def run(self, V, F) -> dict[str, float]:
        from meshrepair import denoise

        self.acc, self.main = {}, False
        self.install()
        t = time.process_time()
        try:
            denoise(V, F)
            raise SystemExit("the main solve was not reached (a plan without main solve?)")
        except _Stop:
            total = time.process_time() - t
        finally:
            self.uninstall()
        out = dict(self.acc)
        out[REST] = out.get(REST, 0.0) + total - sum(self.acc.values())
        out["set-up without the probe's iterations"] = total - out.get(PROBE_ITERS, 0.0)
        out["set-up with the probe's iterations"] = total
        return out


def _load(base: str, lv: int):
    C.generate_subprocess(base, lv, 0.3)
    _, Vn, F, _, _ = C.subdivided_noisy(base, lv, 0.3)
    return Vn, F


def measure(mesh: str, repeats: int) -> dict:
    base, lv = mesh.split(":")
    tm = SetupTimer()
    tm.run(*_load(base, max(int(lv) - 1, 0)))  # warm-up: kernels loaded, lazy imports done
    V, F = _load(base, int(lv))
    runs = [tm.run(V, F) for _ in range(repeats)]
    keys = list(dict.fromkeys(k for r in runs for k in r))
    info = C.machine_info()
    return {"mesh": mesh, "n_vertices": len(V), "repeats": repeats, "git": C.git_state(),
            "pkg": C.package_state(),
            "machine": (f"{info.get('cpu')}, {info.get('cores')} cores, load "
                        f"{info.get('loadavg')}, memory probe {info.get('memprobe_ms')} ms"),
            "phases": {k: [r.get(k, 0.0) for r in runs] for k in keys}}


def table(results: list[dict], names: list[str]) -> str:
    keys = list(dict.fromkeys(k for r in results for k in r["phases"]))
    tail = ["set-up without the probe's iterations", "set-up with the probe's iterations"]
    keys = [k for k in keys if k not in tail] + tail
    r0 = results[0]
    out = [f"Set-up of `denoise(V, F)` on `scale:{r0['mesh']}` + γ 0.3 "
           f"({r0['n_vertices']:,} vertices): CPU s, median of {r0['repeats']} calls.", ""]
    for r, n in zip(results, names, strict=True):
        out.append(f"- {n}: {r['git']}; {r['machine']}")
    out += ["", "| phase | " + " | ".join(names) + " |",
            "|---|" + "---:|" * len(names)]
    for k in keys:
        cells = []
        for r in results:
            v = r["phases"].get(k)
            cells.append("–" if v is None else f"{np.median(v):.2f}")
        b = k in tail
        out.append(f"| {'**' + k + '**' if b else k} | "
                   + " | ".join(f"**{c}**" if b else c for c in cells) + " |")
    return "\n".join(out)


def _paired(args) -> int:
    """``--pairs`` alternating fresh processes on ``--old`` and on this checkout."""
    import os
    import subprocess
    import tempfile

    runs: dict[str, list[dict]] = {"old": [], "new": []}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.pairs):
            for which in ("old", "new"):
                out = Path(tmp) / f"{which}{i}.json"
                env = dict(os.environ)
                if which == "old":
                    env["PYTHONPATH"] = str(Path(args.old).resolve())
                subprocess.run([sys.executable, __file__, "--mesh", args.mesh, "--repeats", "1",
                                "--json", str(out)], env=env, check=True,
                               stdout=subprocess.DEVNULL)
                runs[which].append(json.loads(out.read_text()))
    res = []
    for which, rs in runs.items():
        r = dict(rs[-1])
        keys = list(dict.fromkeys(k for x in rs for k in x["phases"]))
        r["phases"] = {k: [x["phases"].get(k, [0.0])[0] for x in rs] for k in keys}
        r["repeats"] = len(rs)
        r["git"] = f"{r['git']} ({which}: {rs[-1].get('pkg', '')})"
        res.append(r)
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1))
    print(table(res, ["before", "after"]))
    print(f"\n{args.pairs} pairs of fresh processes, alternating; 'before' = the package at "
          f"{args.old}.")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mesh", default="twelve:4", help="BASE:LEVELS (subdivided, γ 0.3)")
    ap.add_argument("--repeats", type=int, default=3, help="timed calls (median)")
    ap.add_argument("--json", help="also write the measurements here")
    ap.add_argument("--table", nargs="+", metavar="JSON", help="print saved measurements")
    ap.add_argument("--old", metavar="SRC", help="also measure the package at SRC, paired")
    ap.add_argument("--pairs", type=int, default=3, help="with --old: process pairs")
    args = ap.parse_args(argv)
    if args.old:
        return _paired(args)
    if args.table:
        res, names = [], []
        for p in args.table:
            r = json.loads(Path(p).read_text())
            rs = r if isinstance(r, list) else [r]  # a paired file holds both columns
            res += rs
            names += ([f"{Path(p).stem}:{n}" for n in ("before", "after")] if len(rs) == 2
                      else [Path(p).stem])
        print(table(res, names))
        return 0
    C.limit_threads(1)
    r = measure(args.mesh, args.repeats)
    if args.json:
        Path(args.json).write_text(json.dumps(r, indent=1))
    print(table([r], ["CPU s"]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
