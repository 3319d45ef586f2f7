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

from meshrepair.commands.common import angle_degrees
from meshrepair.errors import MeshRepairError

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
        from meshrepair.io import check_input_file

        check_input_file(p)
    except ImportError:  # meshrepair.io not available
        if not p.is_file():
            raise MeshRepairError(f"mesh file {str(p)!r} does not exist; check the path") from None
    try:
        from meshrepair.io import read_mesh
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
    from meshrepair.commands.common import output_path

    return output_path(out, inputs, force=force, suffixes=suffixes)


def sharp_edges(V: np.ndarray, F: np.ndarray, threshold: float = 30.0) -> np.ndarray:
    """Sharp-edge mask M_E ``(nE,)`` bool (dihedral angle above ``threshold`` degrees)."""
    from meshrepair.mesh.geometry import face_normals, sharp_edge_mask
    from meshrepair.mesh.topology import edge_topology

    return sharp_edge_mask(face_normals(V, F), edge_topology(F, len(V)), threshold) > 0.5


def reference_metrics(V: np.ndarray, F: np.ndarray, V_ref: np.ndarray,
                      F_ref: np.ndarray) -> dict[str, float] | None:
    """MSAE (degrees², face normals over ``F``) and E_V against ``(V_ref, F_ref)``; None unless
    both have the same vertex count and the same faces (vertex i of one is vertex i of the
    other: a reference stored with another vertex order compares by distances only)."""
    from meshrepair.metrics import msae, vertex_error

    if not same_connectivity(V, F, V_ref, F_ref):
        return None
    return {"MSAE": msae(V, V_ref, F), "E_V": vertex_error(V, V_ref)}


def same_connectivity(V, F, V_ref, F_ref) -> bool:
    """Same vertex count and the same face array: per-vertex and per-face errors are defined."""
    return V.shape == V_ref.shape and F.shape == F_ref.shape and bool(np.array_equal(F, F_ref))


def connectivity_note(V, F, V_ref, F_ref) -> str:
    """Why :func:`reference_metrics` is None, in a few words."""
    if len(V) != len(V_ref):
        return f"{len(V)} vs {len(V_ref)} vertices"
    return "different faces or vertex order"


def _color_options(color: str, mesh: LoadedMesh) -> dict:
    if color in ("curvature", "none"):
        return {"color_by": color}
    if color.lower().endswith(".npy"):
        from meshrepair.io import check_input_file

        p = check_input_file(color, "--color ")
        try:
            s = np.load(p, allow_pickle=False)
        except (OSError, ValueError) as exc:
            raise MeshRepairError(f"cannot read {color!r} as a numpy array: {exc}") from exc
        if s.dtype.kind not in "biuf":  # strings, complex, records: not values to colour by
            raise MeshRepairError(f"{color!r} holds {s.dtype} values; --color needs one real "
                                  "number (or bool) per vertex")
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
                   help="camera rotation about +y in degrees (0: looking down -z; default: "
                   "the object's front, upright; see docs/viewer.md)")
    p.add_argument("--elevation", type=float, default=None,
                   help="camera tilt towards +y in degrees (0 when --azimuth is given; "
                   "default: the object's front, upright)")
    p.add_argument("--sharp-edges", action="store_true",
                   help="overlay the sharp-edge mask M_E (dihedral angle above --sharp-threshold)")
    p.add_argument("--sharp-threshold", type=angle_degrees, default=30.0, metavar="DEG",
                   help="dihedral angle threshold for --sharp-edges (default 30)")
    p.add_argument("--supersample", type=int, default=1, choices=(1, 2, 3),
                   help="anti-aliasing factor (default 1)")
    p.add_argument("--force", action="store_true", help="overwrite the PNG if it exists")
    a = p.add_argument_group("aiming the camera (instead of fitting the whole mesh)")
    a.add_argument("--view-dir", default=None, metavar="DX,DY,DZ",
                   help="direction the camera looks in, the object's up kept vertical "
                   "(replaces --azimuth/--elevation; "
                   "write --view-dir=-1,0,0 when it starts with a minus); default with "
                   "--frame-*: straight at the region, against its normal")
    a.add_argument("--look-at", default=None, metavar="X,Y,Z",
                   help="point at the centre of the picture (needs --radius; "
                   "--look-at=-1,0,0 for a leading minus)")
    a.add_argument("--radius", type=float, default=None, metavar="R",
                   help="radius of the sphere around --look-at (or the framed region) that "
                   "fills the picture")
    a.add_argument("--frame-hole", type=int, default=None, metavar="N",
                   help="frame hole N of the (first) mesh, numbered as 'meshrepair fill --list'")
    a.add_argument("--frame-region", default=None, metavar="ATTR|FILE.npy",
                   help="frame the vertices where a 0/1 mask is set: a per-vertex attribute of "
                   "the (first) mesh (e.g. 'filled') or a .npy mask (per vertex or per face)")
    a.add_argument("--frame-scale", type=float, default=1.25, metavar="S",
                   help="with --frame-*: the picture shows S times the region's radius "
                   "(default 1.25)")
    a.add_argument("--no-clip", action="store_true",
                   help="with --look-at/--frame-*: keep the geometry between the camera and the "
                   "region (default: clipped away)")


def _vec3(text: str, what: str) -> np.ndarray:
    try:
        v = np.array([float(t) for t in text.replace(" ", "").split(",")])
    except ValueError:
        v = np.zeros(0)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise MeshRepairError(f"{what} needs 3 comma-separated numbers, got {text!r}")
    return v


def _region_frame(spec: str, mesh: LoadedMesh):
    """Frame of the mask ``spec`` (vertex attribute name or .npy file) on ``mesh``."""
    from meshrepair.render.framing import frame_faces, frame_vertices

    if spec.lower().endswith(".npy"):
        p = Path(spec)
        if not p.is_file():
            raise MeshRepairError(f"--frame-region file {spec!r} does not exist")
        m = np.asarray(np.load(p, allow_pickle=False)).ravel()
    elif spec in mesh.vertex_attributes:
        m = np.asarray(mesh.vertex_attributes[spec]).ravel()
    else:
        names = ", ".join(sorted(mesh.vertex_attributes)) or "none"
        raise MeshRepairError(f"--frame-region {spec!r} is neither a .npy file nor a vertex "
                              f"attribute of the mesh (attributes: {names})")
    sel = np.nan_to_num(m.astype(np.float64)) > 0.5
    if not sel.any():
        raise MeshRepairError(f"--frame-region {spec!r} selects nothing (no value above 0.5)")
    if len(sel) == len(mesh.V):
        return frame_vertices(mesh.V, mesh.F, sel, name=spec)
    if len(sel) == len(mesh.F):
        return frame_faces(mesh.V, mesh.F, sel, name=spec)
    raise MeshRepairError(f"--frame-region {spec!r} has {len(sel)} values; the mesh has "
                          f"{len(mesh.V)} vertices and {len(mesh.F)} faces")


def aim_options(args: argparse.Namespace, mesh: LoadedMesh) -> dict:
    """Camera keywords of :func:`meshrepair.render.render_mesh` from the aiming options."""
    from meshrepair.render.framing import frame_hole

    framed = [o for o in ("look_at", "frame_hole", "frame_region")
              if getattr(args, o, None) is not None]
    if len(framed) > 1:
        raise MeshRepairError("give only one of --look-at, --frame-hole, --frame-region")
    if args.view_dir is not None and (args.azimuth is not None or args.elevation is not None):
        raise MeshRepairError("give either --view-dir or --azimuth/--elevation, not both")
    if not (np.isfinite(args.frame_scale) and args.frame_scale > 0):
        raise MeshRepairError(f"--frame-scale must be > 0, got {args.frame_scale}")
    kw: dict = {"azimuth": args.azimuth, "elevation": args.elevation}
    if args.view_dir is not None:
        kw = {"view_dir": _vec3(args.view_dir, "--view-dir")}
    if args.radius is not None and not (np.isfinite(args.radius) and args.radius > 0):
        raise MeshRepairError(f"--radius must be a number > 0, got {args.radius}")
    if args.look_at is not None:
        if args.radius is None:
            raise MeshRepairError("--look-at needs --radius R (the size of the part to show)")
        kw.update(look_at=_vec3(args.look_at, "--look-at"), radius=args.radius)
    elif framed:
        fr = (frame_hole(mesh.V, mesh.F, args.frame_hole) if args.frame_hole is not None
              else _region_frame(args.frame_region, mesh))
        r = args.radius if args.radius is not None else fr.radius * args.frame_scale
        kw.update(look_at=fr.center, radius=r)
        if fr.normal is not None and "view_dir" not in kw and args.azimuth is None \
                and args.elevation is None:
            kw = {"view_dir": -fr.normal, "look_at": fr.center, "radius": r}
    elif args.radius is not None:
        raise MeshRepairError("--radius needs --look-at or --frame-hole/--frame-region")
    if "look_at" in kw:
        kw["clip"] = not args.no_clip
    return kw


# --------------------------------------------------------------------------------------------
# render


def run_render(args: argparse.Namespace) -> int:
    """Handler of ``meshrepair render``; returns the exit code."""
    from meshrepair.render import render_mesh, save_png

    color_file = args.color if args.color.lower().endswith(".npy") else None
    out = check_output_path(args.output, [args.input, color_file], (".png",), args.force)
    t0 = time.perf_counter()
    mesh = load_mesh(args.input)
    kw = _color_options(args.color, mesh)
    if "scalars" in kw:
        kw["colorbar_label"] = Path(args.color).stem if args.color.endswith(".npy") else args.color
    if args.sharp_edges:
        kw["edge_mask"] = sharp_edges(mesh.V, mesh.F, args.sharp_threshold)
    w, h = args.size
    kw.update(aim_options(args, mesh))
    img = render_mesh(
        mesh.V, mesh.F, shading=args.shading,
        width=w, height=h, title=args.title, supersample=args.supersample, **kw,
    )  # fmt: skip
    save_png(out, img, overwrite=args.force)
    print(f"wrote {out} ({img.shape[1]}x{img.shape[0]}, {time.perf_counter() - t0:.2f} s)")
    return 0


def run_compare(args: argparse.Namespace) -> int:
    """Handler of ``meshrepair compare``; returns the exit code."""
    from meshrepair.render import compare_figure

    if len(args.paths) < 2:
        raise MeshRepairError("compare needs at least one mesh and the output: A [B ...] OUT.png")
    inputs, out = args.paths[:-1], args.paths[-1]
    out = check_output_path(out, [*inputs, args.reference], (".png",), args.force)
    if args.titles is not None and len(args.titles) != len(inputs):
        raise MeshRepairError(
            f"--titles has {len(args.titles)} entries for {len(inputs)} meshes; give one per mesh"
        )
    t0 = time.perf_counter()
    meshes = [load_mesh(p) for p in inputs]
    color = _compare_colors(args.color, meshes, inputs)
    titles = args.titles if args.titles is not None else [Path(p).stem for p in inputs]
    metrics = None
    if args.reference is not None:
        ref = load_mesh(args.reference)
        metrics = []
        for m in meshes:
            r = reference_metrics(m.V, m.F, ref.V, ref.F)
            if r is None:
                metrics.append(f"n/a ({connectivity_note(m.V, m.F, ref.V, ref.F)})")
            else:
                metrics.append(f"MSAE {r['MSAE']:.4g} deg²\nE_V {r['E_V']:.4g}")
    edge_masks = None
    if args.sharp_edges:
        edge_masks = [sharp_edges(m.V, m.F, args.sharp_threshold) for m in meshes]
    w, h = args.size
    img = compare_figure(
        [(m.V, m.F) for m in meshes], titles, metrics=metrics, out_path=out,
        shading=args.shading, width=w, height=h, edge_mask=edge_masks,
        supersample=args.supersample, **color, **aim_options(args, meshes[0]),
        overwrite=args.force,
    )  # fmt: skip
    print(f"wrote {out} ({img.shape[1]}x{img.shape[0]}, {time.perf_counter() - t0:.2f} s)")
    return 0


def _compare_colors(color: str, meshes: list[LoadedMesh], paths: list) -> dict:
    """compare --color: curvature, none, a vertex attribute (NaN, drawn grey, on meshes without
    it), one .npy for every mesh, or comma-separated .npy files, one per mesh."""
    if color in ("curvature", "none"):
        return {"color_by": color}
    files = [c for c in color.split(",") if c]
    if all(c.lower().endswith(".npy") for c in files) and files:
        if len(files) not in (1, len(meshes)):
            raise MeshRepairError(f"--color has {len(files)} .npy files for {len(meshes)} meshes;"
                                  " give one for all or one per mesh")
        files = files * len(meshes) if len(files) == 1 else files
        scal = [_color_options(f, m)["scalars"] for f, m in zip(files, meshes, strict=True)]
        return {"color_by": "scalars", "scalars": scal, "colorbar_label": Path(files[0]).stem}
    have = [color in m.vertex_attributes for m in meshes]
    if not any(have):
        raise MeshRepairError(
            f"--color {color!r} is not 'curvature', 'none', .npy file(s) or a vertex attribute of "
            "any of the meshes")
    scal = []
    for m, ok, p in zip(meshes, have, paths, strict=True):
        if ok:
            scal.append(np.asarray(m.vertex_attributes[color], dtype=np.float64).ravel())
        else:
            print(f"note: {p} has no vertex attribute {color!r}; drawn grey")
            scal.append(np.full(len(m.V), np.nan))
    return {"color_by": "scalars", "scalars": scal, "colorbar_label": color}


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
    c.add_argument("--color", default="curvature", metavar="curvature|none|ATTR|A.npy[,B.npy]",
                   help="'curvature' (default), 'none', a per-vertex attribute of the meshes "
                   "(e.g. 'filled'; grey where a mesh lacks it), or .npy values: one file for "
                   "all meshes or one per mesh, comma-separated")
    c.add_argument("--size", nargs=2, type=int, default=(600, 600), metavar=("W", "H"),
                   help="size of ONE panel in pixels (default 600 600)")
    _add_view_options(c)
    c.set_defaults(func=run_compare)
