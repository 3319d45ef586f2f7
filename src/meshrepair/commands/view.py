"""``meshrepair view``: one offline HTML page showing meshes side by side in 3-D.

Example
-------
``meshrepair view bunny.ply bunny_filled.ply -o view.html``
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from meshrepair.commands.common import angle_degrees
from meshrepair.errors import MeshRepairError

_SUFFIXES = (".html", ".htm")


def run_view(args: argparse.Namespace) -> int:
    """Handler of ``meshrepair view``; returns the exit code."""
    from meshrepair.commands.common import output_path
    from meshrepair.commands.render import load_mesh, reference_metrics
    from meshrepair.mesh.geometry import edge_lengths
    from meshrepair.mesh.topology import boundary_loops, edge_topology
    from meshrepair.viewer import DEFAULT_FACE_BUDGET, write_viewer
    from meshrepair.viewer.content import mesh_pane, mesh_regions

    if args.output is None:
        raise MeshRepairError("missing output: give -o VIEW.html")
    out = output_path(args.output, [*args.meshes, args.reference], force=args.force,
                      suffixes=_SUFFIXES)
    if not 1 <= len(args.meshes) <= 8:
        raise MeshRepairError(f"view shows 1 to 8 meshes, got {len(args.meshes)}")
    if args.titles is not None and len(args.titles) != len(args.meshes):
        raise MeshRepairError(f"--titles has {len(args.titles)} entries for {len(args.meshes)} "
                              "meshes; give one per mesh")
    budget = DEFAULT_FACE_BUDGET if args.face_budget is None else args.face_budget
    if budget < 100:
        raise MeshRepairError(f"--face-budget must be at least 100, got {budget}")
    t0 = time.perf_counter()
    titles = args.titles or [Path(p).name for p in args.meshes]
    meshes = [load_mesh(p) for p in args.meshes]
    ref = load_mesh(args.reference) if args.reference else None
    panes, regions, details = [], [], []
    metrics: dict[str, list] = {"vertices": [], "faces": [], "boundary loops": [],
                                "mean edge length": []}
    if ref is not None:
        metrics["MSAE vs reference (deg²)"] = []
        metrics["E_V vs reference"] = []
    multi = len(meshes) > 1
    for title, m in zip(titles, meshes, strict=True):
        pane = mesh_pane(m.V, m.F, title, attributes=m.vertex_attributes,
                         sharp_threshold=args.sharp_threshold)
        panes.append(pane)
        fr, de = mesh_regions(m.V, m.F, highlight=pane.highlight,
                              label=pane.highlight_label.replace(" faces", ""),
                              prefix=f"{title}: " if multi else "")
        regions += fr
        details += de
        metrics["vertices"].append(len(m.V))
        metrics["faces"].append(len(m.F))
        metrics["boundary loops"].append(len(boundary_loops(m.F, len(m.V))))
        # the unique edges from the (compiled) edge table: 0.1 s at 1M faces, not 3.7 s
        metrics["mean edge length"].append(
            float(edge_lengths(m.V, edge_topology(m.F, len(m.V)).edges).mean()))
        if ref is not None:
            r = reference_metrics(m.V, m.F, ref.V, ref.F)
            metrics["MSAE vs reference (deg²)"].append(r["MSAE"] if r else "n/a")
            metrics["E_V vs reference"].append(r["E_V"] if r else "n/a")
    write_viewer(out, panes, regions, region_details=details, metrics=metrics,
                 title=args.title or "meshrepair view: " + ", ".join(titles),
                 face_budget=budget)
    size = out.stat().st_size / 2**20
    print(f"wrote {out} ({len(panes)} panes, {len(regions)} holes/regions, {size:.1f} MB, "
          f"{time.perf_counter() - t0:.2f} s)")
    return 0


def register(subparsers) -> None:
    """Add the ``view`` sub-command to an argparse ``subparsers`` object."""
    p = subparsers.add_parser(
        "view",
        help="write an interactive 3-D viewer (one offline HTML file) of meshes side by side",
        description="Write ONE self-contained HTML page (opens offline, no server) showing the "
        "meshes side by side with linked cameras: orbit, pan and zoom all panes together, "
        "flat/smooth shading, wireframe, curvature or attribute colouring, the sharp edges "
        "M_E, filled/template faces highlighted, and a list of holes/regions to go to.",
    )
    p.add_argument("meshes", nargs="+", metavar="MESH", help="mesh files (1 to 8)")
    p.add_argument("-o", "--output", default=None, metavar="VIEW.html", help="page to write")
    p.add_argument("--titles", nargs="+", default=None, help="one title per mesh")
    p.add_argument("--title", default=None, help="page title")
    p.add_argument("--reference", default=None, metavar="REF",
                   help="ground truth: MSAE and E_V of meshes with its vertices and faces")
    p.add_argument("--sharp-threshold", type=angle_degrees, default=30.0, metavar="DEG",
                   help="dihedral angle of the sharp-edge overlay M_E (default 30)")
    p.add_argument("--face-budget", type=int, default=None, metavar="N",
                   help="show a decimated copy of meshes with more than N faces (default "
                   "300000; the page says so)")
    p.add_argument("--force", action="store_true", help="overwrite the output if it exists")
    p.set_defaults(func=run_view)
