#!/usr/bin/env python
"""Colours and texture coordinates on filled holes (issue 27): cut, fill, interpolate, compare.

A shared mesh gets a smooth colour field and a texture-coordinate field that are known
functions of the position (:func:`colour_field`, :func:`uv_field`; colours stored as uchar, as
scanners write them). Holes are cut with the protocol of ``benchmarks/compare.py``
(:func:`compare.cut_discs`: 3 geodesic discs, seed 7), filled with
:func:`meshrepair.fill_holes` at its defaults, and the attributes are carried to the result by
:func:`meshrepair.io.carry_attributes` with each ``--methods`` interpolation (biharmonic, the
default, and harmonic). On the
new vertices the interpolated values are compared with the field at their final positions:

* ``colour mean / max``: absolute error per channel, in % of that channel's range over the
  mesh (uchar rounding, 0.2 % of a full range, included);
* ``uv mean / max``: the same for the two texture coordinates;
* ``geom mean``: symmetric mean distance between the new faces and the removed ones, in 1e-3
  of the bounding-box diagonal (:func:`meshrepair.metrics.distances`), beside them.

Usage: ``python benchmarks/attributes.py [--meshes spot,nefertiti,igea] [--radii 4,8,16]``
(about a minute); prints a markdown table.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _common  # noqa: E402  (limits BLAS threads before numpy is imported)
import numpy as np  # noqa: E402

from meshrepair.fill import fill_holes  # noqa: E402
from meshrepair.io import MeshData, carry_attributes, read_mesh  # noqa: E402
from meshrepair.metrics import distances  # noqa: E402

RGB = ("red", "green", "blue")


def colour_field(V: np.ndarray, lo: np.ndarray, diag: float) -> np.ndarray:
    """RGB in [0, 1]: one period of a sine across the bounding-box diagonal, a different
    direction per channel."""
    X = (V - lo) / diag
    return np.stack([0.5 + 0.45 * np.sin(2 * np.pi * (X[:, 0] + 0.3 * X[:, 1])),
                     0.5 + 0.45 * np.sin(2 * np.pi * (X[:, 1] - 0.2 * X[:, 2]) + 1.0),
                     0.5 + 0.45 * np.cos(2 * np.pi * (X[:, 2] + 0.5 * X[:, 0]))], axis=1)


def uv_field(V: np.ndarray, lo: np.ndarray, diag: float) -> np.ndarray:
    """Texture coordinates: a planar projection with a smooth wave on v."""
    X = (V - lo) / diag
    return np.stack([X[:, 0] + 0.2 * X[:, 2],
                     X[:, 1] + 0.05 * np.sin(2 * np.pi * X[:, 2])], axis=1)


def measure(name: str, radius: float, *, n_discs: int = 3, seed: int = 7,
            methods: tuple[str, ...] = ("biharmonic",)) -> list[dict]:
    """Cut ``n_discs`` discs of ``radius`` mean edge lengths from shared mesh ``name``, fill
    them, carry the colour and UV fields over with each interpolation method; errors on the
    new vertices (module docstring), one dict per method."""
    from compare import cut_discs

    m = read_mesh(_common.mesh_path(name))
    lo = m.V.min(axis=0)
    diag = float(np.linalg.norm(m.V.max(axis=0) - lo))
    hc = cut_discs(name, m.V, m.F, n_discs=n_discs, radius=radius, seed=seed)
    C = np.rint(colour_field(hc.Vc, lo, diag) * 255).astype(np.uint8)
    UV = uv_field(hc.Vc, lo, diag).astype(np.float32)
    src = MeshData(V=hc.Vc, F=hc.Fc, vertex_attributes={
        **{n: C[:, k] for k, n in enumerate(RGB)}, "s": UV[:, 0], "t": UV[:, 1]})
    t0 = time.perf_counter()
    res = fill_holes(hc.Vc, hc.Fc)
    t_fill = time.perf_counter() - t0
    patch = _compact(res.V, res.F[res.new_faces])
    truth = _compact(m.V, m.F[hc.removed])
    geom = 1e3 * distances(*patch, *truth)["mean"] / diag
    new = res.new_vertices
    Vn = res.V[new]
    c_true, uv_true = colour_field(Vn, lo, diag), uv_field(Vn, lo, diag)
    c_rng = np.ptp(colour_field(m.V, lo, diag), axis=0)
    uv_rng = np.ptp(uv_field(m.V, lo, diag), axis=0)
    rows = []
    for method in methods:
        t0 = time.perf_counter()
        out = carry_attributes(src, res, interpolation=method)
        t_carry = time.perf_counter() - t0
        c_got = np.stack([out.vertex_attributes[n][new] for n in RGB], axis=1) / 255.0
        uv_got = np.stack([out.vertex_attributes[n][new] for n in ("s", "t")], axis=1)
        ce = np.abs(c_got - c_true) / c_rng
        ue = np.abs(uv_got - uv_true) / uv_rng
        rows.append({"mesh": name, "radius": radius, "method": method,
                     "holes": f"{res.n_filled}/{len(res.holes)}", "new_vertices": int(len(new)),
                     "colour_mean": 100 * float(ce.mean()), "colour_max": 100 * float(ce.max()),
                     "uv_mean": 100 * float(ue.mean()), "uv_max": 100 * float(ue.max()),
                     "geom_mean": geom, "t_fill": t_fill, "t_carry": t_carry})
    return rows


def _compact(V, F):
    u = np.unique(F.ravel())
    idx = -np.ones(len(V), np.int64)
    idx[u] = np.arange(len(u))
    return V[u], idx[F]


HEADER = ("| mesh | radius | method | holes | new V | colour mean % | colour max % | uv mean % | "
          "uv max % | geom mean e-3 | fill s | carry s |\n"
          "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")


def row(r: dict) -> str:
    return (f"| {r['mesh']} | {r['radius']:g} | {r['method']} | {r['holes']} | "
            f"{r['new_vertices']} | "
            f"{r['colour_mean']:.2f} | {r['colour_max']:.2f} | {r['uv_mean']:.2f} | "
            f"{r['uv_max']:.2f} | {r['geom_mean']:.3f} | {r['t_fill']:.2f} | "
            f"{r['t_carry']:.3f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--meshes", default="spot,nefertiti,igea")
    ap.add_argument("--radii", default="4,8,16")
    ap.add_argument("--methods", default="biharmonic,harmonic")
    a = ap.parse_args()
    _common.limit_threads(1)
    print(HEADER)
    for name in a.meshes.split(","):
        for r in a.radii.split(","):
            for x in measure(name, float(r), methods=tuple(a.methods.split(","))):
                print(row(x), flush=True)


if __name__ == "__main__":
    main()
