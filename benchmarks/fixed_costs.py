"""Fixed costs of a process that uses meshrepair (issue 15): start-up, numba, first vs warm call.

Each figure is CPU time (``time.process_time``) of one step in a *fresh* Python process, the
median over ``--runs`` processes, so the figures hold on a loaded machine better than wall time.
Steps, in the order a ``denoise`` process pays them:

* ``import numpy``; ``import meshrepair`` (lazy: the package alone); ``import scipy.sparse``
  (as the solver does); ``import numba``; ``import meshrepair._kernels`` (creating the cached
  dispatchers);
* numba's set-up on the first cached kernel (whether it imported ``scipy.linalg``: numba's BLAS
  check), then a further kernel load (the median of the next three);
* ``import scipy.linalg`` after ``scipy.sparse`` in a process without numba (what that check
  adds);
* ``from meshrepair import denoise``, and the first and a warm default ``denoise`` call on a
  benchmark mesh (twelve + γ 0.3, 4,610 vertices, cached by ``benchmarks/denoise.py``), with the
  number of kernels loaded by the first call;
* the command line: ``main(["--version"])`` of ``meshrepair.cli``.

Usage::

    python benchmarks/fixed_costs.py [--runs 7] [--mesh twelve:0]

Prints a markdown table and the machine line with the memory probe (benchmarks/_common.py).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402, I001  (sets the thread env vars before numpy is imported)
import numpy as np  # noqa: E402

PROBE = r'''
import json, os, sys, time
c = time.process_time
out = {}
t = c(); import numpy as np; out["import numpy"] = c() - t
t = c(); import meshrepair; out["import meshrepair (package)"] = c() - t
t = c(); import scipy.sparse; out["import scipy.sparse (the solver imports it)"] = c() - t
t = c(); import numba; out["import numba"] = c() - t
t = c(); import meshrepair._kernels as K; out["create the cached dispatchers"] = c() - t
had = "scipy.linalg" in sys.modules
V = np.random.default_rng(0).random((10, 3)); E = np.array([[0, 1], [1, 2]])
F = np.array([[0, 1, 2]])
t = c(); K.edge_lengths(V, E); out["numba set-up (first cached kernel)"] = c() - t
out["set-up imported scipy.linalg"] = float(not had and "scipy.linalg" in sys.modules)
loads = []
for f in (lambda: K.face_normals(V, F), lambda: K.vertex_normals(V, F),
          lambda: K.face_area2_lmax2(V, F)):
    t = c(); f(); loads.append(c() - t)
out["a further kernel load"] = sorted(loads)[1]
print("RESULT " + json.dumps(out))
'''

SCIPY_LINALG = r'''
import json, time
import numpy, scipy.sparse
t = time.process_time(); import scipy.linalg
print("RESULT " + json.dumps({"import scipy.linalg after scipy.sparse, no numba":
                              time.process_time() - t}))
'''

CALLS = r'''
import json, sys, time
c = time.process_time
import numpy as np
from threadpoolctl import threadpool_limits
z = np.load(sys.argv[1])
t = c(); from meshrepair import denoise; imp = c() - t
import numba.core.caching as nc
n = [0]
orig = nc.Cache.load_overload
def counted(self, *a, **k):
    n[0] += 1
    return orig(self, *a, **k)
nc.Cache.load_overload = counted
with threadpool_limits(1):
    t = c(); denoise(z["Vn"], z["F"]); first = c() - t
    loads = n[0]
    t = c(); denoise(z["Vn"], z["F"]); warm = c() - t
print("RESULT " + json.dumps({"from meshrepair import denoise": imp, "first denoise call": first,
      "warm denoise call": warm, "first call - warm call": first - warm,
      "kernels loaded by the first call": loads}))
'''

CLI = r'''
import json, time
t = time.process_time()
import contextlib, io
from meshrepair.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    try:
        main(["--version"])
    except SystemExit:
        pass
print("RESULT " + json.dumps({"CLI main(['--version'])": time.process_time() - t}))
'''


def _run(code: str, *args: str) -> dict:
    p = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True)
    for line in p.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    raise SystemExit(f"probe failed (exit {p.returncode}): {p.stderr.strip()[-500:]}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=7, help="fresh processes per probe (median)")
    ap.add_argument("--mesh", default="twelve:0", help="BASE:LEVELS of the benchmark mesh")
    args = ap.parse_args(argv)
    base, lv = args.mesh.split(":")
    C.generate_subprocess(base, int(lv), 0.3)
    npz = str(C.CACHE / f"{base}_sub{int(lv)}_g0.3_s0.npz")
    _run(CALLS, npz)  # fill numba's disk cache (a fresh copy compiles once)
    rows: dict[str, list[float]] = {}
    for _ in range(args.runs):
        for code, extra in ((PROBE, ()), (SCIPY_LINALG, ()), (CALLS, (npz,)), (CLI, ())):
            for k, v in _run(code, *extra).items():
                rows.setdefault(k, []).append(v)
    info = C.machine_info()
    print(f"machine: {info.get('cpu')}, {info.get('cores')} cores, load {info.get('loadavg')}, "
          f"memory probe {info.get('memprobe_ms')} ms, package {info.get('pkg')}\n")
    print(f"| step (fresh process, mesh {base} ×{lv} + γ 0.3) | CPU ms, median | min–max |")
    print("|---|---:|---:|")
    for k, v in rows.items():
        if k.startswith("set-up imported") or k.startswith("kernels loaded"):
            print(f"| {k} | {np.median(v):.0f} | {min(v):.0f}–{max(v):.0f} |")
        else:
            print(f"| {k} | {1e3 * np.median(v):.1f} | {1e3 * min(v):.1f}–{1e3 * max(v):.1f} |")
    print(f"\n{args.runs} fresh processes per probe; 'set-up imported scipy.linalg' is 1 when "
          "numba's first-kernel set-up imported it (its BLAS check).")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
