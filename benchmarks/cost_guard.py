"""Issue 12's cost guard, paired: the default ``denoise`` of two source trees on the same inputs,
whole processes alternating (old, new, old, new, ...), the CPU time and peak RSS of each
process from the operating system (``os.wait4``), and per pair the ratio new / old.

Each process is ``benchmarks/_ab.py NPZ K`` (import, ``K`` default denoise calls) with
``PYTHONPATH`` set to the tree; the first, untimed, process of each tree fills numba's cache so
no compile time is counted. Quote the median ratio (the machine is shared: the table prints the
load average and the memory probe before and after).

Usage::

    python benchmarks/cost_guard.py --old /work/wt/base1bdd/src --new src \\
        --case twelve_sub4_g0.3_s0.npz:1 --case nllr_nicolo.npz:4 --pairs 3

``--case NPZ:K`` (an ``.npz`` with keys ``Vn`` and ``F``, as ``benchmarks/denoise.py`` caches
them; a relative path is looked up in ``$TMPDIR/meshrepair-bench-cache``): ``K`` calls per
process (``K > 1``: the warm calls 2..K are also reported, as ``_ab.py`` prints them).
``--warm NPZ`` runs the cache-filling process on a smaller input (the kernels' types do not
depend on the size).
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402, I001  (sets the thread env vars before numpy is imported)

AB = str(Path(__file__).resolve().parent / "_ab.py")


def run_once(tree: str, npz: str, k: int) -> tuple[float, float, float | None]:
    """CPU seconds (user + sys) and peak RSS (MB) of one ``_ab.py`` process on ``tree``, and
    the median warm-call CPU it prints (``None`` when ``k == 1``)."""
    env = dict(os.environ, PYTHONPATH=str(Path(tree).resolve()), OPENBLAS_NUM_THREADS="1",
               NUMBA_NUM_THREADS="1")
    p = subprocess.Popen([sys.executable, AB, npz, str(k)], env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True)
    out = p.stdout.read()
    _, status, ru = os.wait4(p.pid, 0)
    p.stdout.close()
    if status != 0:
        raise SystemExit(f"_ab.py failed on {tree} ({npz}):\n{out}")
    m = re.search(r"warm call CPU s: min [0-9.]+ median ([0-9.]+)", out)
    return ru.ru_utime + ru.ru_stime, ru.ru_maxrss / 1024, float(m.group(1)) if m else None


def resolve(npz: str) -> str:
    p = Path(npz)
    if not p.is_absolute() and not p.exists():
        p = Path(tempfile.gettempdir()) / "meshrepair-bench-cache" / npz
    if not p.exists():
        raise SystemExit(f"no such input: {npz}")
    return str(p)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", required=True, help="source tree of the reference (its src/)")
    ap.add_argument("--new", required=True, help="source tree measured (its src/)")
    ap.add_argument("--case", action="append", required=True, help="NPZ:K, repeatable")
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--warm", default=None,
                    help="NPZ of the untimed cache-filling process (default: each case's own)")
    a = ap.parse_args()
    info = C.machine_info()
    print(f"old {a.old}, new {a.new}; load {info.get('loadavg')}, memory probe "
          f"{info['memprobe_ms']} ms, git {info['git']}\n")
    rows = []
    for case in a.case:
        npz, _, k = case.partition(":")
        npz, k = resolve(npz), int(k or 1)
        for tree in (a.old, a.new):  # fill numba's cache of each tree first (not timed)
            run_once(tree, resolve(a.warm) if a.warm else npz, 1)
        old, new, ratios, w_old, w_new, rss = [], [], [], [], [], []
        for _ in range(a.pairs):
            co, ro, wo = run_once(a.old, npz, k)
            cn, rn, wn = run_once(a.new, npz, k)
            old.append(co)
            new.append(cn)
            ratios.append(cn / co)
            rss.append((ro, rn))
            if wo is not None:
                w_old.append(wo)
                w_new.append(wn)
        row = (f"| {Path(npz).name} (K={k}) | " + " / ".join(f"{x:.2f}" for x in old) + " | "
               + " / ".join(f"{x:.2f}" for x in new) + " | "
               + ", ".join(f"{r:.3f}" for r in ratios)
               + f" | **{statistics.median(ratios):.3f}** | ")
        if w_old:
            row += (" / ".join(f"{x:.4f}" for x in w_old) + " → "
                    + " / ".join(f"{x:.4f}" for x in w_new)
                    + f" ({statistics.median(w_new) / statistics.median(w_old):.3f})")
        else:
            row += "—"
        row += f" | {max(r[0] for r in rss):,.0f} / {max(r[1] for r in rss):,.0f} |"
        rows.append(row)
        print(row, flush=True)
    info = C.machine_info()
    print(f"\nafter: load {info.get('loadavg')}, memory probe {info['memprobe_ms']} ms\n")
    print("| case | old process CPU s | new process CPU s | ratio per pair | median | warm-call "
          "CPU s old → new (ratio of medians) | peak RSS MB old / new |")
    print("|---|---|---|---|---:|---|---|")
    for row in rows:
        print(row)


if __name__ == "__main__":
    main()
