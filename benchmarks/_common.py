"""Shared helpers of the benchmark scripts (not part of the package).

Every benchmark limits BLAS/OpenMP to one thread *before* numpy is imported (the machine is
shared; one thread also makes timings comparable), reads the shared meshes from
``../shared/meshes`` (override with ``MESHREPAIR_SHARED_MESHES``) and calls only the public API
of :mod:`meshrepair` (``read_mesh``, ``write_mesh``, ``add_noise``, ``denoise``, ``msae``,
``vertex_error``), so the scripts keep working while the solver internals change.

Run as a script, this module is the *worker* of ``benchmarks/denoise.py``: each benchmark case
runs in a fresh process so that ``ru_maxrss`` (the process's resident-memory high-water mark)
measures that case alone::

    python benchmarks/_common.py --worker '{"name": ..., "kind": "pair", ...}'

prints one line ``RESULT {json}``.
"""

from __future__ import annotations

import os

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS",
           "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import gc  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import resource  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MESHES = Path(os.environ.get("MESHREPAIR_SHARED_MESHES", ROOT.parent / "shared" / "meshes"))
CACHE = Path(os.environ.get("MESHREPAIR_BENCH_CACHE",
                            Path(tempfile.gettempdir()) / "meshrepair-bench-cache"))

_LIMITER = None


def keyword_option(text: str) -> tuple[str, object]:
    """``KEY=VALUE`` of a ``--option`` argument as ``(key, value)``: the value read as a Python
    literal (``3``, ``0.5``, ``False``, ``(1, 2)``), else kept as the string."""
    import ast

    key, sep, value = text.partition("=")
    if not sep or not key:
        raise SystemExit(f"--option takes KEY=VALUE, not {text!r}")
    try:
        return key, ast.literal_eval(value)
    except (ValueError, SyntaxError):
        return key, value


def limit_threads(n: int = 1) -> None:
    """Limit every BLAS/OpenMP pool loaded so far (and later, via the env vars) to ``n``."""
    global _LIMITER
    _LIMITER = threadpool_limits(n)


def mesh_path(name: str) -> Path:
    """``fandisk`` -> ``MESHES/fandisk.ply``; ``noisy/x`` -> ``MESHES/noisy/x.ply``."""
    p = MESHES / (name if name.endswith(".ply") else name + ".ply")
    if not p.exists():
        raise SystemExit(f"shared mesh {p} is missing: set MESHREPAIR_SHARED_MESHES to the folder "
                         "holding the shared meshes")
    return p


def read(name: str):
    """Read a shared mesh; returns ``(V, F, seconds)``."""
    from meshrepair import read_mesh

    t = time.perf_counter()
    m = read_mesh(mesh_path(name))
    return m.V, m.F, time.perf_counter() - t


def subdivided_noisy(base: str, levels: int, gamma: float, seed: int = 0):
    """Midpoint-subdivide a shared mesh ``levels`` times, add normal noise γ (seed fixed).

    Cached as ``.npz`` in ``CACHE`` (the generation of a 4M-vertex mesh takes a while and its
    memory peak must not pollute the worker's ``ru_maxrss``). Returns
    ``(V_clean, V_noisy, F, seconds_to_generate_or_load, cached)``.
    """
    import trimesh.remesh

    from meshrepair import add_noise

    CACHE.mkdir(parents=True, exist_ok=True)
    f = CACHE / f"{base}_sub{levels}_g{gamma:g}_s{seed}.npz"
    t = time.perf_counter()
    if f.exists():
        z = np.load(f)
        return z["V"], z["Vn"], z["F"], time.perf_counter() - t, True
    V, F, _ = read(base)
    for _ in range(levels):
        V, F = trimesh.remesh.subdivide(V, F)
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    Vn = add_noise(V, F, gamma, direction="normal", seed=seed)
    tmp = f.with_suffix(".tmp.npz")
    np.savez(tmp, V=V, Vn=Vn, F=F)
    tmp.replace(f)
    return V, Vn, F, time.perf_counter() - t, False


def write_text(path, text: str) -> Path:
    """Write a benchmark's output (a table or JSON it regenerates) atomically, through the
    project's one output rule (:func:`meshrepair.atomic.atomic_write`): an interrupted run never
    leaves a half-written file. Benchmarks overwrite their own outputs by design (re-runs)."""
    from meshrepair.atomic import atomic_write

    with atomic_write(path, "w", encoding="utf-8") as fh:
        fh.write(text)
    return Path(path)


def rss_now_mb() -> float:
    """Current resident set size (MiB), from /proc (Linux)."""
    try:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
    except OSError:
        return float("nan")


def reset_peak_rss() -> bool:
    """Reset this process's resident high-water mark (Linux ``/proc/self/clear_refs`` 5), so that
    :func:`peak_rss_mb` then reports the peak of what follows only; False if unsupported.

    Needed because ``ru_maxrss`` never decreases: after the warm-up, the package hands freed
    memory back to the kernel (``malloc_trim``), and ``ru_maxrss`` minus the current RSS would
    count that returned memory as part of the next call's peak."""
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
        return True
    except OSError:
        return False


def peak_rss_mb() -> float:
    """VmHWM (MiB): the resident high-water mark since the last :func:`reset_peak_rss`."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return float("nan")


def maxrss_mb() -> float:
    """``ru_maxrss`` of this process in MiB (Linux reports KiB, macOS bytes)."""
    r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return r / 2**20 if sys.platform == "darwin" else r / 1024


def machine_info() -> dict:
    """CPU model, core count, load average, RAM: printed with every benchmark table."""
    info = {"python": platform.python_version(), "numpy": np.__version__,
            "cores": os.cpu_count(), "git": git_state(), "pkg": package_state()}
    for mod in ("scipy", "numba"):
        try:
            info[mod] = __import__(mod).__version__
        except ImportError:
            info[mod] = None
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    info["cpu"] = line.split(":", 1)[1].strip()
                    break
        with open("/proc/meminfo") as fh:
            info["ram_gb"] = round(int(fh.readline().split()[1]) / 2**20, 1)
        info["loadavg"] = tuple(round(x, 2) for x in os.getloadavg())
    except OSError:
        pass
    info["memprobe_ms"] = memory_probe()
    return info


def memory_probe(n: int = 7_000_000, repeats: int = 5) -> float:
    """Milliseconds for one random gather-and-sum over ``n`` float64 (56 MB), minimum of
    ``repeats``: the memory-bound kind of work an ADMM iteration at a million vertices is made of.
    This shared VM's speed for such work varies up to 2x from one hour to the next (measured:
    the same 1.18M-vertex run took 57 s and 94 s within 15 minutes), so every table records the
    probe taken just before it; compare timings only between runs with similar probes."""
    rng = np.random.default_rng(0)
    x = rng.random(n)
    idx = np.sort(rng.integers(0, n, n)) ^ (np.arange(n) & 255)  # local but not sequential
    idx = np.clip(idx, 0, n - 1)
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        float(x[idx].sum())
        best = min(best, time.perf_counter() - t)
    return round(best * 1000, 1)


def warm_imports(jit: bool = True) -> float:
    """Import what ``denoise`` imports lazily and, with ``jit``, run a tiny denoise (642-vertex
    noisy icosphere, both stages) so that compiled kernels (numba, if the package uses it) are
    loaded before anything is timed. Returns the seconds this took."""
    t = time.perf_counter()
    import scipy.optimize  # noqa: F401
    import scipy.sparse.csgraph  # noqa: F401
    import scipy.sparse.linalg  # noqa: F401

    import meshrepair  # noqa: F401
    import meshrepair.denoise.api  # noqa: F401
    import meshrepair.mesh.validate  # noqa: F401
    import meshrepair.model.relax  # noqa: F401

    if jit:
        import trimesh

        from meshrepair import add_noise, denoise

        ico = trimesh.creation.icosphere(subdivisions=3)
        V = np.asarray(ico.vertices, dtype=np.float64)
        F = np.asarray(ico.faces, dtype=np.int64)
        denoise(add_noise(V, F, 0.3, seed=1), F, robust_iters=2, feature_iters=4)
    return time.perf_counter() - t


def package_state() -> str:
    """Where ``meshrepair`` is imported from and a hash of its ``.py`` files, e.g.
    ``/work/main/src/meshrepair@3fa2b1c0d9``: rows measured on different code differ here
    (run against a frozen copy with ``PYTHONPATH=/copy/src``)."""
    import hashlib

    import meshrepair

    pkg = Path(meshrepair.__file__).resolve().parent
    h = hashlib.sha1()
    for f in sorted(pkg.rglob("*.py")):
        h.update(str(f.relative_to(pkg)).encode())
        h.update(f.read_bytes())
    tag = pkg.parent / "COMMIT"  # a frozen copy may say which commit it was taken from
    origin = f" (copy of {tag.read_text().strip()})" if tag.is_file() else ""
    return f"{pkg}@{h.hexdigest()[:10]}{origin}"


def git_state() -> str:
    """``<commit>`` plus ``+dirty(<hash of the diff of src/>)`` when src/ has local changes."""
    import hashlib
    import subprocess

    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, text=True,
                              capture_output=True, check=True).stdout.strip()
        diff = subprocess.run(["git", "diff", "HEAD", "--", "src"], cwd=ROOT,
                              capture_output=True, check=True).stdout
        untracked = subprocess.run(["git", "ls-files", "--others", "--exclude-standard", "src"],
                                   cwd=ROOT, capture_output=True, text=True,
                                   check=True).stdout.split()
        h = hashlib.sha1(diff)
        for f in sorted(untracked):
            h.update((ROOT / f).read_bytes())
        return head + (f"+dirty({h.hexdigest()[:8]})" if diff or untracked else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


# --------------------------------------------------------------------------------------------
# worker: one benchmark case in a fresh process
# --------------------------------------------------------------------------------------------

def _load_case(spec: dict):
    """Returns ``V_in, F, V_truth, io_read_s, prep_s, input_file``."""
    from meshrepair import add_noise

    kind = spec["kind"]
    if kind == "pair":
        Vn, F, t_read = read(spec["noisy"])
        Vt, Ft, _ = read(spec["truth"])
        if not np.array_equal(F, Ft):
            raise SystemExit(f"{spec['noisy']} and {spec['truth']} do not share faces")
        return Vn, F, Vt, t_read, 0.0, str(mesh_path(spec["noisy"]))
    if kind == "synthetic":
        Vt, F, t_read = read(spec["truth"])
        t = time.perf_counter()
        Vn = add_noise(Vt, F, spec["gamma"], direction=spec["direction"], seed=spec["seed"])
        return Vn, F, Vt, t_read, time.perf_counter() - t, str(mesh_path(spec["truth"]))
    if kind == "scaling":
        Vt, Vn, F, t_gen, _ = subdivided_noisy(spec["base"], spec["levels"], spec["gamma"],
                                               spec["seed"])
        return Vn, F, Vt, float("nan"), t_gen, None
    raise SystemExit(f"unknown case kind {kind!r}")


def run_case(spec: dict) -> dict:
    """Run one case (see ``benchmarks/denoise.py`` for the spec keys); returns a result dict."""
    limit_threads(1)
    t_warm = warm_imports()
    from meshrepair import denoise, msae, read_mesh, vertex_error, write_mesh

    Vn, F, Vt, t_read, t_prep, _ = _load_case(spec)
    kw = dict(spec.get("denoise_kwargs") or {})
    out = {"name": spec["name"], "kind": spec["kind"], "nV": int(len(Vn)), "nF": int(len(F)),
           "prep_s": t_prep, "warmup_s": t_warm, "denoise_kwargs": kw, "pkg": package_state()}

    # ---- timed runs (no tracemalloc); the first one also gives the RSS high-water mark ----
    gc.collect()
    rss_before = rss_now_mb()
    maxrss_before = maxrss_mb()
    hwm_reset = reset_peak_rss()
    totals, loops, iters, per_iter_min = [], [], [], []
    res = None
    for r in range(max(1, int(spec.get("repeats", 3)))):
        res = None
        gc.collect()
        t = time.perf_counter()
        res = denoise(Vn, F, **kw)
        dt = time.perf_counter() - t
        if r == 0:
            maxrss_after = maxrss_mb()
            call_peak = peak_rss_mb() if hwm_reset else maxrss_after
        h = res.history
        loop = h[-1]["time"] if h else 0.0
        totals.append(dt)
        loops.append(loop)
        iters.append(res.iterations)
        if len(h) > 1:
            per_iter_min.append(float(np.min(np.diff([0.0] + [e["time"] for e in h]))))
    best = int(np.argmin(totals))
    out.update(
        iterations=int(iters[best]),
        stop_reason=res.stop_reason,
        stages={s: sum(1 for e in res.history if e["stage"] == s)
                for s in dict.fromkeys(e["stage"] for e in res.history)},
        total_s=float(totals[best]),
        totals=[float(x) for x in totals],
        loop_s=float(loops[best]),
        setup_s=float(totals[best] - loops[best]),
        s_per_iter=float(min(lo / max(it, 1) for lo, it in zip(loops, iters, strict=True))),
        fastest_iter_s=float(min(per_iter_min)) if per_iter_min else float("nan"),
        rss_delta_mb=float(call_peak - rss_before),
        rss_peak_mb=float(maxrss_after),
        rss_peak_is_denoise=bool(maxrss_after > maxrss_before),
        noise_estimate=float(res.noise_estimate),
        lam=float(res.params.get("lam", float("nan"))),
    )
    out["msae_in"] = msae(Vn, Vt, F)
    out["msae_out"] = msae(res.V, Vt, F)
    out["ev_in"] = vertex_error(Vn, Vt)
    out["ev_out"] = vertex_error(res.V, Vt)

    # ---- I/O (not part of the denoise time): read the input PLY, write the result PLY ----
    with tempfile.TemporaryDirectory() as td:
        src = Path(td) / "in.ply"
        if spec["kind"] == "scaling":
            write_mesh(src, Vn, F)
        else:
            src = mesh_path(spec["noisy"] if spec["kind"] == "pair" else spec["truth"])
        t = time.perf_counter()
        read_mesh(src)
        out["io_read_s"] = time.perf_counter() - t
        t = time.perf_counter()
        write_mesh(Path(td) / "out.ply", res.V, res.F)
        out["io_write_s"] = time.perf_counter() - t
    del res

    # ---- tracemalloc peak (numpy buffers are traced too), separate run ----
    if spec.get("trace", True):
        tkw = dict(kw)
        tkw.update(spec.get("trace_kwargs") or {})
        gc.collect()
        tracemalloc.start()
        t = time.perf_counter()
        denoise(Vn, F, **tkw)
        out["trace_s"] = time.perf_counter() - t
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        out["trace_peak_mb"] = peak / 2**20
        out["trace_kwargs"] = tkw
    else:
        out["trace_peak_mb"] = float("nan")
    return out


def run_case_subprocess(spec: dict, timeout: float | None = None) -> dict:
    """Run :func:`run_case` in a fresh interpreter (clean ``ru_maxrss``)."""
    import subprocess

    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", json.dumps(spec)]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=str(ROOT))
    for line in p.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    tail = "\n".join(p.stderr.strip().splitlines()[-15:])
    return {"name": spec["name"], "kind": spec["kind"], "error": f"exit {p.returncode}: {tail}"}


def generate_subprocess(base: str, levels: int, gamma: float, seed: int = 0) -> None:
    """Create the cached subdivided mesh in a separate process (see :func:`subdivided_noisy`)."""
    import subprocess

    here = str(Path(__file__).parent)
    code = (f"import sys; sys.path.insert(0, {here!r}); import _common as c; "
            f"c.subdivided_noisy({base!r}, {int(levels)}, {float(gamma)!r}, {int(seed)})")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=str(ROOT))


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--worker":
        result = run_case(json.loads(sys.argv[2]))
        print("RESULT " + json.dumps(result), flush=True)
    else:
        raise SystemExit(__doc__)
