"""The truth's own folded faces and what the defaults do to them (docs/parameters.md, known limits).

Some clean shared meshes have faces folded over against their neighbours (normal more than 90°
from the sum of the edge-neighbours' normals, :func:`meshrepair.model.relax.locally_flipped_faces`):
tiny, sliver-like faces of the scan. The denoiser treats a fold as noise (it starts from the
untangled input and its prior pulls a face's normal towards its neighbours'), so it turns such a
face over and each one costs up to 180° in the MSAE (33). For every shared clean mesh with such
faces, on the clean input and on white noise of ``--levels`` mean edge lengths (along the normals
and in random directions, seed 1), the table prints the defaults' MSAE, the part of that MSAE
held by the truth's folded faces, and how many of them end more than 90° from the truth.

    python benchmarks/input_folds.py                      # every shared clean mesh with folds
    python benchmarks/input_folds.py --meshes nefertiti --levels 0 0.05 0.2

The machine's memory probe is printed with the table (benchmarks/_common.py).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402, I001  (sets the thread env vars before numpy is imported)
import numpy as np  # noqa: E402


def clean_meshes() -> list[str]:
    """Names of the shared clean meshes (``<name>.ply`` at the top of the meshes folder)."""
    return sorted(p.stem for p in C.MESHES.glob("*.ply"))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="*", default=None, help="default: every clean mesh")
    ap.add_argument("--levels", nargs="*", type=float, default=[0.0, 0.05],
                    help="noise levels in mean edge lengths (0: the clean input)")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    C.limit_threads(1)
    import meshrepair as mr
    from meshrepair.mesh.topology import edge_topology
    from meshrepair.metrics import face_normals
    from meshrepair.model.relax import locally_flipped_faces

    print("machine:", C.machine_info())
    print()
    print("| mesh | truth's folded faces | noise | γ | defaults MSAE | held by the folded faces "
          "| of them > 90° off |")
    print("|---|---:|---|---:|---:|---:|---:|")
    for name in args.meshes or clean_meshes():
        Vt, F, _ = C.read(name)
        folded = locally_flipped_faces(Vt, edge_topology(F, len(Vt)))
        if not folded.any():
            continue
        for g in args.levels:
            for direction in (("normal", "random") if g > 0 else ("clean",)):
                Vn = Vt if g == 0 else mr.add_noise(Vt, F, g, direction=direction,
                                                    seed=args.seed)
                r = mr.denoise(Vn, F)
                cos = np.einsum("ij,ij->i", face_normals(r.V, F), face_normals(Vt, F))
                a2 = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))) ** 2
                print(f"| {name} | {int(folded.sum())} | {direction} | {g:g} | "
                      f"{a2.mean():.2f} | {a2[folded].sum() / len(F):.2f} "
                      f"({100 * a2[folded].sum() / max(a2.sum(), 1e-300):.0f} %) | "
                      f"{int((a2[folded] > 90.0 ** 2).sum())} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
