#!/usr/bin/env python
"""Batch throughput (issue 16): meshes per minute of
``meshrepair.batch.orchestrate.run(task="denoise")``
with 1 and 2 local Dask workers on the shared noisy meshes, the speed-up, and per-worker peak
memory.

The collection is every noisy input of the shared meshes: ``noisy/*.ply`` and
``published/*__noisy.ply`` (15 meshes, 6k to 135k vertices, default denoise, thumbnails and
index.html as a user gets them). Each run starts a LocalCluster of N single-threaded workers,
warms every worker (imports and compiled kernels: a tiny denoise) and then times
``batch.run`` from submission to the last record (``wall``); ``startup`` is the cluster start
and warm-up, reported apart. ``busy`` is the sum of the per-mesh job times (the records'
``seconds``), so ``busy / (N * wall)`` is how well the workers were kept busy; ``CPU/wall per
job`` is the CPU time a job's process got over its wall time (1.0 on an idle machine; lower when
other processes take the cores: with the kernel's autogroup scheduling, a session's processes
share one fair share of the CPUs, so on a machine busy with other sessions a second worker
cannot add CPU time and the speed-up collapses towards 1). ``LPT bound``
is the best speed-up the collection allows: the 1-worker job times scheduled longest first onto
N workers (the meshes are not equal, so the last big mesh bounds the makespan). ``peak MB`` is
the highest per-mesh peak RSS of each worker process (VmHWM reset at the start of every job).

The machine is shared: the load average is printed before and after, with the memory probe of
``benchmarks/_common.py``; quote medians over ``--repeats`` runs.

Usage: ``python benchmarks/batch.py [--repeats 3] [--workers 1,2] [--no-thumbnails]``
(about 2-4 minutes on 2 idle cores).
"""

from __future__ import annotations

import argparse
import heapq
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import MESHES, machine_info  # noqa: E402 - sets the thread variables first


def collection() -> list[Path]:
    paths = sorted((MESHES / "noisy").glob("*.ply")) + sorted(
        (MESHES / "published").glob("*__noisy.ply"))
    if not paths:
        raise SystemExit(f"no shared meshes under {MESHES}: set MESHREPAIR_SHARED_MESHES")
    return paths


def _warm() -> float:
    t = time.perf_counter()
    from _common import warm_imports  # noqa: F401 - path set by the client below

    warm_imports(jit=True)
    return time.perf_counter() - t


def _warm_worker(bench_dir: str) -> float:
    if bench_dir not in sys.path:
        sys.path.insert(0, bench_dir)
    return _warm()


def lpt_makespan(times: list[float], n: int) -> float:
    """Makespan of the longest-processing-time-first schedule of ``times`` on ``n`` workers."""
    bins = [0.0] * n
    for t in sorted(times, reverse=True):
        heapq.heapreplace(bins, bins[0] + t)
    return max(bins)


def one_run(paths: list[Path], n: int, thumbnails: bool) -> dict:
    import meshrepair.batch.orchestrate as batch

    t0 = time.perf_counter()
    with batch.connect(workers=n) as client:
        client.wait_for_workers(n, timeout=120)
        client.run(_warm_worker, str(Path(__file__).resolve().parent))
        startup = time.perf_counter() - t0
        with tempfile.TemporaryDirectory(prefix="mr-batch-bench-") as out:
            t1 = time.perf_counter()
            recs = batch.run(paths, out, task="denoise", client=client, thumbnails=thumbnails)
            wall = time.perf_counter() - t1
    failed = [r for r in recs if r["status"] != "done"]
    if failed:
        raise SystemExit(f"{len(failed)} meshes failed: {failed[0]['rel']}: {failed[0]['error']}")
    peak: dict[str, float] = {}
    for r in recs:
        peak[r["worker"]] = max(peak.get(r["worker"], 0.0), r["peak_rss_mb"] or 0.0)
    return {"n": n, "wall": wall, "startup": startup, "records": recs,
            "busy": sum(r["seconds"] + r.get("thumbnail_seconds", 0.0) for r in recs),
            "cpu": sum(r["cpu_seconds"] for r in recs) / sum(r["seconds"] for r in recs),
            "peak": sorted(peak.values(), reverse=True)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--workers", default="1,2", help="comma-separated worker counts")
    ap.add_argument("--no-thumbnails", action="store_true")
    args = ap.parse_args()
    counts = [int(x) for x in args.workers.split(",")]
    paths = collection()
    info = machine_info()
    print(f"machine: {info.get('cpu')}, {info['cores']} cores, {info.get('ram_gb')} GB; "
          f"load average {info.get('loadavg')}; memory probe {info['memprobe_ms']} ms; "
          f"git {info['git']}")
    sizes = []
    for p in paths:
        from meshrepair import read_mesh

        sizes.append(len(read_mesh(p).V))
    print(f"collection: {len(paths)} meshes from {MESHES} (noisy/*.ply, published/*__noisy.ply),"
          f" {min(sizes)}-{max(sizes)} vertices, {sum(sizes)} in all; task denoise (defaults), "
          f"thumbnails {'off' if args.no_thumbnails else 'on'}")
    runs: dict[int, list[dict]] = {n: [] for n in counts}
    for rep in range(args.repeats):
        for n in counts:  # interleaved, so that load changes hit every worker count alike
            r = one_run(paths, n, not args.no_thumbnails)
            runs[n].append(r)
            print(f"  run {rep + 1}: {n} worker(s): wall {r['wall']:.2f} s "
                  f"(startup {r['startup']:.1f} s), load {os.getloadavg()[0]:.2f}", flush=True)
    base_times = [r["seconds"] + r.get("thumbnail_seconds", 0.0)
                  for r in min(runs[counts[0]], key=lambda r: r["wall"])["records"]]
    med1 = statistics.median(r["wall"] for r in runs[counts[0]])
    print()
    print(f"| workers | wall s (median of {args.repeats}) | meshes/min | speed-up | "
          "busy/(N*wall) | CPU/wall per job | LPT bound | startup s | peak MB per worker |")
    print("|---|---|---|---|---|---|---|---|---|")
    for n in counts:
        walls = [r["wall"] for r in runs[n]]
        med = statistics.median(walls)
        busy = statistics.median(r["busy"] / (n * r["wall"]) for r in runs[n])
        bound = sum(base_times) / lpt_makespan(base_times, n)
        cpu = statistics.median(r["cpu"] for r in runs[n])
        peaks = max((r["peak"] for r in runs[n]), key=lambda p: p[0])
        print(f"| {n} | {med:.2f} ({min(walls):.2f}-{max(walls):.2f}) | "
              f"{60 * len(paths) / med:.1f} | {med1 / med:.2f} | {busy:.2f} | {cpu:.2f} | "
              f"{bound:.2f} | "
              f"{statistics.median(r['startup'] for r in runs[n]):.1f} | "
              f"{', '.join(f'{p:.0f}' for p in peaks)} |")
    print(f"\nload average after: {tuple(round(x, 2) for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
