"""Seed robustness of the denoising defaults (issue 12).

``denoise(V, F)`` at its defaults on ``add_noise(V, F, γ, direction=d, seed=s)`` of the shared
clean meshes, for every γ, direction and seed: one row per (mesh, γ, direction) with the MSAE
(33) of each seed, the row's median and the worst / median ratio. Inputs whose MSAE exceeds
``--flag`` (default 3) times their row's median are listed under the table: a default that
works on one noise draw and fails on another of the same law is a robustness failure.

    python benchmarks/seeds.py                          # 6 meshes x 3 γ x 2 directions x 8 seeds
    python benchmarks/seeds.py --meshes fandisk --gammas 0.3 --directions random
    python benchmarks/seeds.py --json now.json          # rows with the recorded decisions
    python benchmarks/seeds.py --table before.json now.json   # markdown, before -> now

The machine's memory probe is printed with the table (benchmarks/_common.py).
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

MESHES = ("fandisk", "twelve", "sharp_sphere", "trim_star", "spot", "nicolo")
GAMMAS = (0.2, 0.3, 0.4)
DIRECTIONS = ("normal", "random")
SEEDS = tuple(range(1, 9))
KEYS = ("impulsive", "support_fraction", "tangential_ratio", "reanchored",
        "reanchor_ratio_after", "residual_level_ratio", "guidance_passes", "reintegrate_steps",
        "reintegrate_rejected", "result_folds_unfolded")


def run(meshes, gammas, directions, seeds) -> list[dict]:
    from meshrepair import add_noise, denoise, msae, read_mesh

    out = []
    for name in meshes:
        g = read_mesh(C.mesh_path(name))
        for gamma in gammas:
            for d in directions:
                row = {"mesh": name, "gamma": gamma, "direction": d, "msae": [], "params": []}
                t0 = time.perf_counter()
                for s in seeds:
                    V0 = add_noise(g.V, g.F, gamma, direction=d, seed=s)
                    r = denoise(V0, g.F)
                    row["msae"].append(msae(r.V, g.V, g.F))
                    row["params"].append({k: r.params.get(k) for k in KEYS})
                row["seeds"] = list(seeds)
                row["time_s"] = time.perf_counter() - t0
                out.append(row)
                m = float(np.median(row["msae"]))
                print(f"{name} γ{gamma} {d}: median {m:.2f}, worst/median "
                      f"{max(row['msae']) / m:.2f} ({row['time_s']:.1f} s)", file=sys.stderr,
                      flush=True)
    return out


def table(rows: list[dict], flag: float) -> str:
    seeds = rows[0]["seeds"]
    lines = ["| mesh | γ | dir | " + " | ".join(f"s{s}" for s in seeds)
             + " | median | worst / median |",
             "|---|---:|---|" + "---:|" * (len(seeds) + 2)]
    flagged = []
    for r in rows:
        m = float(np.median(r["msae"]))
        cells = []
        for s, v in zip(r["seeds"], r["msae"], strict=True):
            bad = v > flag * m
            cells.append(f"**{v:.1f}**" if bad else f"{v:.1f}")
            if bad:
                flagged.append(f"{r['mesh']} γ{r['gamma']} {r['direction']} seed {s}: "
                               f"{v:.1f} = {v / m:.1f} × median {m:.1f}")
        lines.append(f"| {r['mesh']} | {r['gamma']} | {r['direction']} | " + " | ".join(cells)
                     + f" | {m:.2f} | {max(r['msae']) / m:.2f} |")
    lines.append("")
    lines.append(f"inputs above {flag:g} × their row's median: {len(flagged)}")
    lines += [f"- {f}" for f in flagged]
    return "\n".join(lines)


def compare(before: list[dict], now: list[dict]) -> str:
    """Markdown: per row the median and worst before -> now, and the flagged counts."""
    key = {(r["mesh"], r["gamma"], r["direction"]): r for r in before}
    lines = ["| mesh | γ | dir | median before → now | worst before → now | changed seeds |",
             "|---|---:|---|---|---|---:|"]
    for r in now:
        b = key.get((r["mesh"], r["gamma"], r["direction"]))
        if b is None:
            continue
        pairs = zip(b["msae"], r["msae"], strict=True)
        ch = sum(abs(x - y) > 1e-9 * max(1.0, abs(x)) for x, y in pairs)
        lines.append(f"| {r['mesh']} | {r['gamma']} | {r['direction']} | "
                     f"{np.median(b['msae']):.2f} → {np.median(r['msae']):.2f} | "
                     f"{max(b['msae']):.1f} → {max(r['msae']):.1f} | {ch} |")
    return "\n".join(lines)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="+", default=list(MESHES))
    ap.add_argument("--gammas", nargs="+", type=float, default=list(GAMMAS))
    ap.add_argument("--directions", nargs="+", default=list(DIRECTIONS))
    ap.add_argument("--seeds", nargs="+", type=int, default=list(SEEDS))
    ap.add_argument("--flag", type=float, default=3.0, help="flag MSAE > FLAG × row median")
    ap.add_argument("--json", type=Path, help="write the rows (with decisions) here")
    ap.add_argument("--table", nargs=2, type=Path, metavar=("BEFORE", "NOW"),
                    help="print a before -> now markdown table of two --json files and exit")
    a = ap.parse_args(argv)
    if a.table:
        b, n = (json.loads(p.read_text()) for p in a.table)
        print(compare(b, n))
        print()
        print(table(n, a.flag))
        return
    C.limit_threads(1)
    info = C.machine_info()
    rows = run(a.meshes, a.gammas, a.directions, a.seeds)
    if a.json:
        C.write_text(a.json, json.dumps(rows, indent=1, default=float))
    print(f"machine: {info.get('cpu')}, {info.get('cores')} cores, load {info.get('loadavg')}, "
          f"memory probe {info['memprobe_ms']} ms, git {info['git']}")
    print()
    print(table(rows, a.flag))


if __name__ == "__main__":
    main()
