#!/usr/bin/env python
"""Held-out shapes nobody tuned on: smooth implicit surfaces meshed on the spot, then the table of
``benchmarks/monotone.py`` (defaults against a tuned Taubin filter, monotone in the noise).

The defaults are chosen on the shared meshes; these surfaces are not among them and are not
scans of anything: a genus-3 surface (the smooth union of three overlapping tori), a torus, a
rounded cube (``x⁴ + y⁴ + z⁴ = 1``: flat faces joined by tight blends) and three merged
Gaussian blobs. Each is meshed by marching cubes (PyMeshLab ``create_implicit_surface``, voxel
0.02) and remeshed isotropically to about ``--resolutions`` edges per bounding-box diagonal
(``meshing_isotropic_explicit_remeshing``, 10 iterations), a layout like that of the standard
denoising benchmarks; 130 gives 16-31k vertices, 50 gives 2-4k (a coarse mesh on which the
genus-3 tube is under three edges in radius). The meshes are cached as PLY in
``MESHREPAIR_BENCH_CACHE``; everything after that is ``monotone.py`` with the same options.

    python benchmarks/implicit.py                                  # 2 resolutions, normal noise
    python benchmarks/implicit.py --direction random --levels 0.1 0.2 0.3 --json out.json

Needs the ``bench`` extra (PyMeshLab).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402, I001  (sets the thread env vars before numpy is imported)
import numpy as np  # noqa: E402


def _torus_term(cx: float) -> str:
    return f"exp(-10*((sqrt((x-({cx}))*(x-({cx}))+y*y)-0.8)^2+z*z-0.09))"


SHAPES = {
    "genus3": (f"-ln({_torus_term(-1.2)}+{_torus_term(0)}+{_torus_term(1.2)})/10",
               (-2.6, -1.6, -0.9, 2.6, 1.6, 0.9)),
    "torus": ("(sqrt(x*x+y*y)-1)^2+z*z-0.16", (-1.5, -1.5, -0.5, 1.5, 1.5, 0.5)),
    "rcube": ("x*x*x*x+y*y*y*y+z*z*z*z-1", (-1.2, -1.2, -1.2, 1.2, 1.2, 1.2)),
    "blobs": ("0.5-exp(-4*((x-0.5)*(x-0.5)+y*y+z*z))"
              "-exp(-5*((x+0.4)*(x+0.4)+(y-0.3)*(y-0.3)+z*z))"
              "-exp(-6*(x*x+(y+0.5)*(y+0.5)+(z-0.3)*(z-0.3)))",
              (-1.6, -1.6, -1.4, 1.6, 1.4, 1.4)),
}
"""name -> (implicit function f(x, y, z) in muparser syntax, its zero set the surface;
bounding box of the marching cubes: min x, y, z, max x, y, z)."""


def build(name: str, per_diagonal: float) -> Path:
    """The PLY of shape ``name`` remeshed to about ``per_diagonal`` edges per diagonal (cached).
    Raises ``SystemExit`` when the result is not one closed surface of the expected genus."""
    import pymeshlab

    from meshrepair import write_mesh
    from meshrepair.mesh.topology import boundary_loops

    out = C.CACHE / f"implicit_{name}_{per_diagonal:g}.ply"
    if out.exists():
        return out
    expr, b = SHAPES[name]
    ms = pymeshlab.MeshSet()
    ms.create_implicit_surface(expr=expr, voxelsize=0.02, minx=b[0], miny=b[1], minz=b[2],
                               maxx=b[3], maxy=b[4], maxz=b[5])
    ms.meshing_remove_duplicate_vertices()
    diag = ms.current_mesh().bounding_box().diagonal()
    ms.meshing_isotropic_explicit_remeshing(iterations=10,
                                            targetlen=pymeshlab.PureValue(diag / per_diagonal))
    m = ms.current_mesh()
    V, F = np.asarray(m.vertex_matrix(), np.float64), np.asarray(m.face_matrix(), np.int64)
    E = np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1),
                  axis=0)
    genus = (2 - (len(V) - len(E) + len(F))) / 2
    want = {"genus3": 3, "torus": 1}.get(name, 0)
    if boundary_loops(F, len(V)) or genus != want:
        raise SystemExit(f"{name} at {per_diagonal:g} edges per diagonal: genus {genus}, "
                         f"{len(boundary_loops(F, len(V)))} border loops (want a closed surface "
                         f"of genus {want}); try another resolution")
    C.CACHE.mkdir(parents=True, exist_ok=True)
    write_mesh(str(out), V, F)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--shapes", nargs="*", default=list(SHAPES))
    ap.add_argument("--resolutions", nargs="*", type=float, default=[130.0, 50.0],
                    help="edges per bounding-box diagonal of the remeshed surfaces")
    args, rest = ap.parse_known_args()
    unknown = set(args.shapes) - set(SHAPES)
    if unknown:
        ap.error(f"unknown shapes {sorted(unknown)}; known: {sorted(SHAPES)}")
    paths = [str(build(s, r)) for r in args.resolutions for s in args.shapes]
    cmd = [sys.executable, str(Path(__file__).resolve().parent / "monotone.py"),
           "--meshes", *paths, *rest]
    raise SystemExit(subprocess.call(cmd))


if __name__ == "__main__":
    main()
