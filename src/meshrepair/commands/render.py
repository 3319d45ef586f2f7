"""``meshrepair render`` and ``meshrepair compare``: PNG pictures of meshes.

Examples
--------
``meshrepair render fandisk.ply fandisk.png --sharp-edges --azimuth 30 --elevation 20``

``meshrepair compare noisy.ply ours.ply truth.ply fig.png --titles noisy ours truth
--reference truth.ply``
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from ..errors import MeshRepairError

_COLOR_HELP = (
    "'curvature' (signed mean curvature, default), 'none' (plain grey), a .npy file with one "
    "value per vertex or face, or the name of a per-vertex attribute stored in the mesh file"
)


# --------------------------------------------------------------------------------------------
# shared helpers (also used by commands/report.py)


class LoadedMesh:
    """Vertices ``V (nV, 3)``, faces ``F (nF, 3)`` and per-vertex attributes of a mesh file."""

    def __init__(self, V: np.ndarray, F: np.ndarray, vertex_attributes: dict | None = None):
        self.V = np.asarray(V, dtype=np.float64)
        self.F = np.asarray(F, dtype=np.int64)
        self.vertex_attributes = dict(vertex_attributes or {})


def load_mesh(path: str | os.PathLike) -> LoadedMesh:
    """Read a triangle mesh with :func:`meshrepair.io.read_mesh` (trimesh if that is missing)."""
    p = Path(path)
    try:
        from ..io import check_input_file

        check_input_file(p)
    except ImportError:  # meshrepair.io not available
        if not p.is_file():
            raise MeshRepairError(f"mesh file {str(p)!r} does not exist; check the path") from None
    try:
        from ..io import read_mesh
    except ImportError:  # meshrepair.io not available: fall back to trimesh
        read_mesh = None
    if read_mesh is not None:
        m = read_mesh(p)
        return LoadedMesh(m.V, m.F, getattr(m, "vertex_attributes", None))
    import trimesh

    try:
        m = trimesh.load(str(p), process=False, force="mesh")
    except Exception as exc:  # trimesh raises many types for unreadable files
        raise MeshRepairError(f"cannot read {str(p)!r} as a triangle mesh: {exc}") from exc
    if not isinstance(m, trimesh.Trimesh) or len(m.faces) == 0:
        raise MeshRepairError(f"{str(p)!r} contains no triangle faces; give a triangle mesh")
    attrs = {k: np.asarray(v) for k, v in getattr(m, "vertex_attributes", {}).items()}
    return LoadedMesh(m.vertices, m.faces, attrs)


def check_output_path(out: str | os.PathLike, inputs: list, suffixes: tuple[str, ...],
                      force: bool = False) -> Path:
    """The common output rule (:func:`meshrepair.commands.common.output_path`) for pictures and
    reports: one of ``suffixes``, never an input, an existing file only with ``force``."""
    from .common import output_path

    return output_path(out, inputs, force=force, suffixes=suffixes)


def sharp_edges(V: np.ndarray, F: np.ndarray, threshold: float = 30.0) -> np.ndarray:
    """Sharp-edge mask M_E ``(nE,)`` bool (dihedral angle above ``threshold`` degrees)."""
    from ..geometry import face_normals, sharp_edge_mask
    from ..topology import edge_topology

    return sharp_edge_mask(face_normals(V, F), edge_topology(F, len(V)), threshold) > 0.5


def reference_metrics(V: np.ndarray, F: np.ndarray, V_ref: np.ndarray) -> dict[str, float] | None:
    """MSAE (degrees², face normals over ``F``) and E_V against ``V_ref``; None if nV differs."""
    from ..metrics import msae, vertex_error

    if V_ref.shape != V.shape:
        return None
    return {"MSAE": msae(V, V_ref, F), "E_V": vertex_error(V, V_ref)}


def _color_options(color: str, mesh: LoadedMesh) -> dict:
    if color in ("curvature", "none"):
        return {"color_by": color}
    if color.lower().endswith(".npy"):
        from ..io import check_input_file

        p = check_input_file(color, "--color ")
        try:
            s = np.load(p, allow_pickle=False)
        except (OSError, ValueError) as exc:
            raise MeshRepairError(f"cannot read {color!r} as a numpy array: {exc}") from exc
        return {"color_by": "scalars", "scalars": np.asarray(s, dtype=np.float64).ravel()}
    if color in mesh.vertex_attributes:
        return {
            "color_by": "scalars",
            "scalars": np.asarray(mesh.vertex_attributes[color], dtype=np.float64).ravel(),
        }
    names = ", ".join(sorted(mesh.vertex_attributes)) or "none"
    raise MeshRepairError(
        f"--color {color!r} is not 'curvature', 'none', a .npy file or a vertex attribute of the "
        f"mesh (attributes: {names})"
    )


def _add_view_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--shading", choices=("flat", "smooth"), default="flat",
                   help="per-face or interpolated vertex normals (default flat)")
    p.add_argument("--azimuth", type=float, default=None,
                   help="camera rotation about +y in degrees (default 0: looking down -z)")
    p.add_argument("--elevation", type=float, default=None,
                   help="camera tilt towards +y in degrees (default 0)")
    p.add_argument("--sharp-edges", action="store_true",
                   help="overlay the sharp-edge mask M_E (dihedral angle above --sharp-threshold)")
    p.add_argument("--sharp-threshold", type=float, default=30.0, metavar="DEG",
                   help="dihedral angle threshold for --sharp-edges (default 30)")
    p.add_argument("--supersample", type=int, default=1, choices=(1, 2, 3),
                   help="anti-aliasing factor (default 1)")
    p.add_argument("--force", action="store_true", help="overwrite the PNG if it exists")


# --------------------------------------------------------------------------------------------
# render


def run_render(args: argparse.Namespace) -> int:
    """Handler of ``meshrepair render``; returns the exit code."""
    from ..render import render_mesh, save_png

    color_file = args.color if args.color.lower().endswith(".npy") else None
    out = check_output_path(args.output, [args.input, color_file], (".png",), args.force)
    t0 = time.perf_counter()
    mesh = load_mesh(args.input)
    kw = _color_options(args.color, mesh)
    if args.sharp_edges:
        kw["edge_mask"] = sharp_edges(mesh.V, mesh.F, args.sharp_threshold)
    w, h = args.size
    img = render_mesh(
        mesh.V, mesh.F, shading=args.shading, azimuth=args.azimuth, elevation=args.elevation,
        width=w, height=h, title=args.title, supersample=args.supersample, **kw,
    )  # fmt: skip
    save_png(out, img, overwrite=args.force)
    print(f"wrote {out} ({img.shape[1]}x{img.shape[0]}, {time.perf_counter() - t0:.2f} s)")
    return 0


def run_compare(args: argparse.Namespace) -> int:
    """Handler of ``meshrepair compare``; returns the exit code."""
    from ..render import compare_figure

    if len(args.paths) < 2:
        raise MeshRepairError("compare needs at least one mesh and the output: A [B ...] OUT.png")
    inputs, out = args.paths[:-1], args.paths[-1]
    out = check_output_path(out, [*inputs, args.reference], (".png",), args.force)
    if args.titles is not None and len(args.titles) != len(inputs):
        raise MeshRepairError(
            f"--titles has {len(args.titles)} entries for {len(inputs)} meshes; give one per mesh"
        )
    if args.color not in ("curvature", "none"):
        raise MeshRepairError("compare --color must be 'curvature' or 'none'")
    t0 = time.perf_counter()
    meshes = [load_mesh(p) for p in inputs]
    titles = args.titles if args.titles is not None else [Path(p).stem for p in inputs]
    metrics = None
    if args.reference is not None:
        ref = load_mesh(args.reference)
        metrics = []
        for m in meshes:
            r = reference_metrics(m.V, m.F, ref.V)
            if r is None:
                metrics.append(f"n/a ({len(m.V)} vs {len(ref.V)} vertices)")
            else:
                metrics.append(f"MSAE {r['MSAE']:.4g} deg²\nE_V {r['E_V']:.4g}")
    edge_masks = None
    if args.sharp_edges:
        edge_masks = [sharp_edges(m.V, m.F, args.sharp_threshold) for m in meshes]
    w, h = args.size
    img = compare_figure(
        [(m.V, m.F) for m in meshes], titles, metrics=metrics, out_path=out,
        color_by=args.color, shading=args.shading, azimuth=args.azimuth,
        elevation=args.elevation, width=w, height=h, edge_mask=edge_masks,
        supersample=args.supersample, overwrite=args.force,
    )  # fmt: skip
    print(f"wrote {out} ({img.shape[1]}x{img.shape[0]}, {time.perf_counter() - t0:.2f} s)")
    return 0


def register(subparsers) -> None:
    """Add the ``render`` and ``compare`` sub-commands to an argparse ``subparsers`` object."""
    p = subparsers.add_parser(
        "render",
        help="render a mesh to a PNG picture",
        description="Render a triangle mesh headlessly to PNG (white background, colour bar).",
    )
    p.add_argument("input", help="mesh file to render")
    p.add_argument("output", help="PNG file to write (must differ from the input)")
    p.add_argument("--color", default="curvature", metavar="curvature|none|FILE.npy",
                   help=_COLOR_HELP)
    p.add_argument("--size", nargs=2, type=int, default=(800, 800), metavar=("W", "H"),
                   help="image size in pixels (default 800 800)")
    p.add_argument("--title", default=None, help="text above the picture")
    _add_view_options(p)
    p.set_defaults(func=run_render)

    c = subparsers.add_parser(
        "compare",
        help="render several meshes side by side from the same camera",
        description="Render meshes in one row from the same camera with one colour range "
        "(paper-style figure). The last positional argument is the output PNG.",
    )
    c.add_argument("paths", nargs="+", metavar="MESH", help="meshes to compare, then OUT.png")
    c.add_argument("--titles", nargs="+", default=None, help="one title per mesh (default: stems)")
    c.add_argument("--reference", default=None, metavar="REF",
                   help="ground truth: show MSAE (deg²) and E_V under meshes with its vertex count")
    c.add_argument("--color", default="curvature", choices=("curvature", "none"),
                   help="colouring (default curvature)")
    c.add_argument("--size", nargs=2, type=int, default=(600, 600), metavar=("W", "H"),
                   help="size of ONE panel in pixels (default 600 600)")
    _add_view_options(c)
    c.set_defaults(func=run_compare)
