"""Completion from the intact surface and from symmetry: the numbers and pictures of
docs/completion.md ("Damaged regions" and "Symmetric completion").

    python benchmarks/completion.py                 # tables
    python benchmarks/completion.py --pictures docs/img

Self-completion: a geodesic disc (radius 6 l) of a shared mesh is damaged (dent 2 l, one spike
5 l, Gaussian noise 0.5 l, flattened onto the plane of its boundary) and completed with its own
original surface moved by a random rigid motion, as a bare patch or as a piece of a moved copy of
the mesh; the table gives the largest distance of the result to the original surface over the
bounding-box diagonal, at defaults and with the opt-in ``icp="surface"``. Symmetric completion: a
dented disc (radius 5 l) at least 6 l from the mirror plane, ``template="mirror"``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import _common  # noqa: F401  (limits BLAS threads before numpy)
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from meshrepair.complete.api import complete, extract_patch  # noqa: E402
from meshrepair.complete.correspondence import apply_transform  # noqa: E402
from meshrepair.complete.symmetry import detect_symmetry  # noqa: E402
from meshrepair.errors import MeshRepairError  # noqa: E402
from meshrepair.mesh.geometry import mean_edge_length  # noqa: E402
from meshrepair.metrics import point_to_surface  # noqa: E402
from meshrepair.synthetic import (  # noqa: E402
    DAMAGES,
    damage_region,
    geodesic_disc,
    random_rigid,
    symmetrize,
)


def geodesic(V, F, center, radius):
    return geodesic_disc(V, F, center, radius, return_distances=True)


damage = damage_region


def read(name):
    V, F, _ = _common.read(name)
    return V, F


def self_table(name, centers):
    V, F = read(name)
    l = mean_edge_length(V, F)
    diag = np.linalg.norm(V.max(0) - V.min(0))
    rows = []
    for c in centers:
        faces, d = geodesic(V, F, c, 6 * l)
        T = random_rigid(3, 2 * diag)
        VP, FP = extract_patch(V, F, faces)
        for kind in DAMAGES:
            Vd = damage(V, F, faces, d, 6 * l, kind)
            cells = []
            for tmpl, kw in (((apply_transform(T, VP), FP), {}),
                             ((apply_transform(T, V), F, faces), {}),
                             ((apply_transform(T, VP), FP), {"icp": "surface"})):
                t = time.perf_counter()
                res = complete(Vd, F, faces, tmpl, **kw)
                dt = time.perf_counter() - t
                err = point_to_surface(res.V, V, F).max() / diag
                cells.append((err, res.alignment["boundary_rms"], dt))
            rows.append(f"| {name} | {c} | {kind} | " + " | ".join(
                f"{e:.1e} ({b:.1e} l, {dt:.2f} s)" for e, b, dt in cells) + " |")
    return rows


def mirror_table(label, V, F, k=3):
    l = mean_edge_length(V, F)
    diag = np.linalg.norm(V.max(0) - V.min(0))
    s = detect_symmetry(V, F)
    far = np.flatnonzero(np.abs((V - s["point"]) @ s["normal"]) > 6 * l)
    rows = []
    for c in np.random.default_rng(0).choice(far, k, replace=False):
        faces, d = geodesic(V, F, int(c), 5 * l)
        Vd = damage(V, F, faces, d, 5 * l, "dent")
        t = time.perf_counter()
        res = complete(Vd, F, faces, "mirror")
        dt = time.perf_counter() - t
        err = point_to_surface(res.V, V, F).max() / diag
        a, sy = res.alignment, res.symmetry
        rows.append(f"| {label} | {int(c)} | {sy['residual']:.1e} | {a['boundary_rms']:.2g} | "
                    f"{a['context_rms']:.2g} | {err:.1e} | {dt:.2f} |")
    return rows


def pictures(folder: Path) -> None:
    from meshrepair.render import compare_figure

    folder.mkdir(parents=True, exist_ok=True)

    def closeup(V, F, faces, centre, radius):
        keep = np.flatnonzero((np.linalg.norm(V[F] - centre, axis=2) < radius).all(axis=1))
        return keep

    def view(V, F, faces):
        from meshrepair.mesh.geometry import face_normals_areas

        N, A = face_normals_areas(V, F[faces])
        n = (N * A[:, None]).sum(0)
        n /= np.linalg.norm(n)
        return float(np.degrees(np.arctan2(n[0], n[2]))), float(np.degrees(np.arcsin(n[1])))

    def figure(path, V, F, faces, Vd, res, truth_err, title):
        l = mean_edge_length(V, F)
        c = V[np.unique(F[faces])].mean(0)
        az, el = view(V, F, faces)
        region = np.zeros(len(F), bool)
        region[faces] = True
        k0 = closeup(V, F, faces, c, 14 * l)
        tm = np.zeros(len(res.V), bool)
        tm[res.template_vertices] = True
        k1 = closeup(res.V, res.F, None, c, 14 * l)
        tface = tm[res.F].any(axis=1)
        panels = [extract_patch(V, F, k0), extract_patch(Vd, F, k0),
                  extract_patch(res.V, res.F, k1)]
        compare_figure(panels, ["truth", "damaged region (dent)", title],
                       metrics=["", "", f"max distance to truth {truth_err:.1e} diag"],
                       out_path=path, width=380, height=380, azimuth=az, elevation=el,
                       shading="smooth", colorbar=False,
                       region_mask=[region[k0], region[k0], tface[k1]])
        print(f"wrote {path}", flush=True)

    # from a template: fandisk, the region's own surface moved far away
    V, F = read("fandisk")
    l = mean_edge_length(V, F)
    diag = np.linalg.norm(V.max(0) - V.min(0))
    faces, d = geodesic(V, F, 2000, 6 * l)
    Vd = damage(V, F, faces, d, 6 * l, "dent")
    VP, FP = extract_patch(V, F, faces)
    res = complete(Vd, F, faces, (apply_transform(random_rigid(3, 2 * diag), VP), FP))
    err = point_to_surface(res.V, V, F).max() / diag
    figure(folder / "complete_template_fandisk.png", V, F, faces, Vd, res, err,
           "completed from a moved template")
    # from symmetry: spot (mirror-symmetric as it is)
    V, F = read("spot")
    l = mean_edge_length(V, F)
    diag = np.linalg.norm(V.max(0) - V.min(0))
    faces, d = geodesic(V, F, 1869, 5 * l)
    Vd = damage(V, F, faces, d, 5 * l, "dent")
    res = complete(Vd, F, faces, "mirror")
    err = point_to_surface(res.V, V, F).max() / diag
    figure(folder / "complete_mirror_spot.png", V, F, faces, Vd, res, err,
           "completed from its mirror image")


def main() -> None:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pictures", metavar="DIR", default=None,
                    help="only write the pictures of docs/completion.md into DIR")
    args = ap.parse_args()
    if args.pictures:
        pictures(Path(args.pictures))
        return
    print("max distance to truth / diag (boundary residual, time): bare patch | moved piece "
          "(context rings) | bare patch with icp='surface'")
    print("| mesh | centre | damage | default, patch | default, piece | icp='surface' |")
    print("|---|---:|---|---:|---:|---:|")
    for name, centers in (("spot", (100, 1500, 2500)), ("fandisk", (2000, 4000, 6000))):
        print("\n".join(self_table(name, centers)), flush=True)
    print("\n| mesh | centre | symmetry residual (l) | boundary residual (l) | context residual "
          "(l) | max distance / diag | time (s) |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    print("\n".join(mirror_table("spot", *read("spot"))), flush=True)
    print("\n".join(mirror_table("fandisk, one half mirrored", *symmetrize(*read("fandisk")))),
          flush=True)
    print("\n".join(mirror_table("trim_star", *read("trim_star"))), flush=True)
    for name in ("fandisk", "rocker_arm", "screwdriver"):
        V, F = read(name)
        faces, _ = geodesic(V, F, 100, 5 * mean_edge_length(V, F))
        try:
            complete(V, F, faces, "mirror")
            print(f"{name}: accepted")
        except MeshRepairError as exc:
            print(f"{name}: refused: {exc}")


if __name__ == "__main__":
    main()
