"""One process for paired old-vs-new timing: import meshrepair, then ``K`` default denoise calls
on a cached benchmark mesh (``$TMPDIR/meshrepair-bench-cache/*.npz``, made by the scaling rows of
``benchmarks/denoise.py``). Time it from outside, old and new copies alternating, e.g.::

    for i in 1 2 3; do
      PYTHONPATH=/tmp/base  /usr/bin/time -f "old %U s" python benchmarks/_ab.py M.npz 8
      PYTHONPATH=/tmp/after /usr/bin/time -f "new %U s" python benchmarks/_ab.py M.npz 8
    done

Arguments: ``NPZ K [ITERS]`` (``ITERS`` > 0 caps the schedule at ITERS/2 robust + ITERS/2
feature iterations; 0 or absent: the full default schedule).

Each call prints one line: its wall time, the time and iterations of each solver run inside it
(with the default schedule: the robust probe, then the main run) and the rest (validation,
topology, ordering, noise statistics, regions, unfolding), and the process's peak RSS so far.
With ``K > 1`` it also prints the CPU time of the warm calls (min and median of calls 2..K), so
alternating old and new processes also gives the warm-call ratio without the fixed costs::

    for i in 1 2 3 4 5; do
      PYTHONPATH=/tmp/base  python benchmarks/_ab.py M.npz 6
      PYTHONPATH=/tmp/after python benchmarks/_ab.py M.npz 6
    done
"""

import os
import sys

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

if __name__ == "__main__":
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    z = np.load(sys.argv[1])
    Vn, F = z["Vn"], z["F"]
    k = int(sys.argv[2])
    its = int(sys.argv[3]) if len(sys.argv) > 3 else 0
    import resource
    import time

    import meshrepair.model.solver as solver
    from meshrepair import denoise

    runs = []
    orig = solver.ADMMSolver.solve

    def timed_solve(self, *a, **kw):
        t = time.perf_counter()
        r = orig(self, *a, **kw)
        runs.append((time.perf_counter() - t, r.iterations))
        return r

    solver.ADMMSolver.solve = timed_solve
    orig_resume = getattr(solver.ADMMSolver, "resume", None)  # a resumed run

    def timed_resume(self, state, **kw):
        t, k1 = time.perf_counter(), state.k
        r = orig_resume(self, state, **kw)
        runs.append((time.perf_counter() - t, r.iterations - k1))
        return r

    if orig_resume is not None:
        solver.ADMMSolver.resume = timed_resume
    kw = {} if its == 0 else {"robust_iters": its // 2, "feature_iters": its - its // 2}
    cpu = []
    with threadpool_limits(1):
        for _ in range(k):
            runs.clear()
            t0, c0 = time.perf_counter(), time.process_time()
            denoise(Vn, F, **kw)
            total = time.perf_counter() - t0
            cpu.append(time.process_time() - c0)
            rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
            print(f"denoise {total:.2f} s; solver runs: "
                  + ", ".join(f"{s:.2f} s ({n} its)" for s, n in runs)
                  + f"; outside them {total - sum(s for s, _ in runs):.2f} s; "
                  f"peak RSS {rss:.0f} MB", flush=True)
    if k > 1:  # the warm calls (all but the first), for paired in-process comparisons
        w = sorted(cpu[1:])
        print(f"warm call CPU s: min {w[0]:.4f} median {w[len(w) // 2]:.4f}")
