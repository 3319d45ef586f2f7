"""``meshrepair complete``: replace a region of a mesh with a template patch (context-aware
completion, paper Sect. 5).

Examples
--------
``meshrepair complete damaged.ply patch.ply out.ply --region region.txt --mode adaptive``

``meshrepair complete scan.ply patch.ply out.ply --hole 0 --transform place.txt``

``meshrepair complete damaged.ply out.ply --region region.txt --mirror`` (the template is the
mirror image of the region's counterpart across the mesh's symmetry plane)
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

import numpy as np

from meshrepair.errors import MeshRepairError

log = logging.getLogger(__name__)


def run_complete(args: argparse.Namespace) -> int:
    """Handler of ``meshrepair complete``; returns the exit code."""
    from meshrepair.commands.common import ProgressBar, run_outputs, write_json_log
    from meshrepair.complete.api import complete
    from meshrepair.complete.files import template_vertex_map
    from meshrepair.io import read_mesh, write_like_input

    paths = list(args.paths)
    if args.mirror:
        if len(paths) != 1:
            raise MeshRepairError("with --mirror give IN OUT only (the template is the mirrored "
                                  f"counterpart of the region), got {len(paths)} paths after IN")
        args.template, args.output = None, paths[0]
    else:
        if len(paths) != 2:
            raise MeshRepairError("give IN TEMPLATE OUT (or IN OUT --mirror for symmetric "
                                  f"completion), got {len(paths) + 1} paths")
        args.template, args.output = paths
    out, log_path, report_path = run_outputs(
        args, [args.input, args.template, args.region, args.transform, args.template_region],
        output=args.output)
    t0 = time.perf_counter()
    mesh = read_mesh(args.input)
    tmesh = read_mesh(args.template) if args.template is not None else None
    from meshrepair.complete.files import complete_arguments, output_attributes

    template, kw = complete_arguments(mesh, tmesh, complete_options(args))
    t_read = time.perf_counter() - t0
    bar = ProgressBar(args.iterations, "blend", enabled=not args.quiet)
    try:
        res = complete(mesh.V, mesh.F, template=template, callback=bar, **kw)
    finally:
        bar.close()
    t_solve = time.perf_counter() - t0 - t_read
    if res.stop_reason == "interrupted" and not args.save_on_interrupt:
        print("interrupted: nothing written (pass --save-on-interrupt to keep the current "
              "iterate of the blend)", file=sys.stderr)
        return 130
    write_like_input(out, mesh, res, extra=output_attributes(res, out), force=args.force,
                     template=tmesh, template_map=template_vertex_map(tmesh, template, res))
    c = res.correspondence
    if log_path is not None:
        corr = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in c.items()}
        run = {
            "history": res.history,
            "parameters": {**res.params, "input": str(args.input),
                           "template": str(args.template) if args.template else "mirror"},
            "timings": {"read": t_read, "complete": t_solve,
                        "total": time.perf_counter() - t0},
            "metrics": {"seam vertices": c["n_seam"], "rms boundary before": c["rms_before"],
                        "rms boundary after": c["rms_after"], "strip vertices":
                        int(len(res.strip_vertices)), "iterations": res.iterations},
            "correspondence": corr,
            "alignment": res.alignment,
            "symmetry": _jsonable(res.symmetry),
        }
        write_json_log(log_path, run, force=args.force)
    print(f"wrote {out}: {len(res.V)} vertices, {len(res.F)} faces; seam {c['n_seam']} vertices "
          f"(hole {c['n_hole']}, template {c['n_template']}), boundary RMS {c['rms_before']:.3g} "
          f"-> {c['rms_after']:.3g}, {res.iterations} iterations "
          f"({time.perf_counter() - t0:.2f} s)")
    print(alignment_summary(res))
    from meshrepair.commands.common import write_run_report

    tmpl_v = np.zeros(len(res.V), bool)
    tmpl_v[res.template_vertices] = True
    a = res.alignment
    write_run_report(
        report_path, force=args.force, title=f"meshrepair complete {Path(args.input).name}",
        highlight=tmpl_v[res.F].all(axis=1), highlight_label="template faces",
        sharp_mask=res.M_E,
        input_mesh=(mesh.V, mesh.F), output_mesh=(res.V, res.F),
        masks={"M_V": res.M_V, "M_E": res.M_E}, history=res.history, parameters=res.params,
        metrics={"seam vertices": c["n_seam"], "rms boundary before": c["rms_before"],
                 "rms boundary after": c["rms_after"], "iterations": res.iterations,
                 "alignment residual boundary (l)": a["boundary_rms"],
                 "alignment residual context (l)": ("n/a" if a["context_rms"] is None
                                                    else a["context_rms"])},
        timings={"total": time.perf_counter() - t0})
    return 0


def _jsonable(d):
    if d is None:
        return None
    return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in d.items()}


def alignment_summary(res) -> str:
    """One line: the alignment residuals (and the symmetry plane) in mean edge lengths."""
    a = res.alignment
    ctx = ("no template context" if a.get("context_rms") is None
           else f"context rings {a['context_rms']:.3g} (max {a['context_max']:.3g})")
    line = (f"alignment residual (mean edge lengths): boundary {a['boundary_rms']:.3g} (max "
            f"{a['boundary_max']:.3g}), {ctx}")
    if a.get("warning"):
        line += " -- LARGE: check the template"
    if res.symmetry is not None:
        s = res.symmetry
        n = np.round(np.asarray(s["normal"]), 4).tolist()
        line += (f"\nsymmetry plane: normal {n}, offset {s['offset']:.6g}; symmetry residual "
                 f"{s['residual']:.3g} mean edge lengths")
    return line


def add_complete_options(p, *, required: bool = True) -> None:
    """The completion options of ``meshrepair complete`` (shared with ``meshrepair batch``)."""
    from meshrepair.complete.modes import ICP_MODES, MODES, ORIENTATIONS  # not the task: no numba

    g = p.add_mutually_exclusive_group(required=required)
    g.add_argument("--region", metavar="FILE",
                   help="faces to replace: a text file of face indices, or a .ply/.npy "
                   "per-vertex mask (the faces with all three vertices selected)")
    g.add_argument("--hole", type=int, metavar="K",
                   help="complete the existing hole K instead (numbered as 'meshrepair fill "
                   "--list' shows them: 0 = longest)")
    p.add_argument("--template-region", metavar="FILE", default=None,
                   help="use only these faces of TEMPLATE (same formats as --region)")
    p.add_argument("--mirror", action="store_true",
                   help="symmetric completion: the template is the mirror image of the "
                   "region's counterpart across the mesh's symmetry plane (refused when the "
                   "mesh is not symmetric enough)")
    p.add_argument("--max-symmetry-residual", type=float, default=0.1, metavar="L",
                   help="with --mirror: largest accepted symmetry residual in mean edge "
                   "lengths (default 0.1)")
    p.add_argument("--strip-rings", type=int, default=2, metavar="K",
                   help="width of the blending strip in edge rings on each side (default 2)")
    p.add_argument("--mode", choices=MODES, default="adaptive",
                   help="M_E on the strip: smooth joint, sharp joint, or dihedral threshold "
                   "(default adaptive)")
    p.add_argument("--transform", metavar="FILE", default=None,
                   help="4x4 matrix placing the template (16 numbers, row-major, as text or a "
                   ".npy array); skips the automatic alignment")
    p.add_argument("--allow-scale", action="store_true",
                   help="fit a uniform scale too and accept any size ratio")
    p.add_argument("--orientation", choices=ORIENTATIONS, default="template",
                   help="trust the template's face orientation (default) or try both")
    p.add_argument("--icp", choices=ICP_MODES, default="auto",
                   help="alignment refinement (default auto = context: the hole's boundary and "
                   "the intact rings around it, never the region's faces; 'surface' also fits "
                   "the region's faces, for an undamaged region)")
    p.add_argument("--iterations", type=int, default=80, metavar="N",
                   help="ADMM iterations of the blending (default 80)")
    p.add_argument("--th", type=float, default=30.0, metavar="DEG",
                   help="dihedral threshold of the adaptive M_E (default 30)")
    p.add_argument("--denoise", action="store_true",
                   help="solve on the whole mesh with the denoising schedule")


def complete_options(args: argparse.Namespace) -> dict:
    """``region``, ``hole``, ``template_region``, ``mirror`` and the keyword arguments of
    :func:`meshrepair.complete` from the parsed options (see
    :func:`meshrepair.complete.files.complete_arguments`)."""
    return dict(region=args.region, hole=args.hole, template_region=args.template_region,
                mirror=args.mirror, transform=args.transform, strip_rings=args.strip_rings,
                mode=args.mode, allow_scale=args.allow_scale, orientation=args.orientation,
                icp=args.icp, iterations=args.iterations, th=args.th, denoise=args.denoise,
                max_symmetry_residual=args.max_symmetry_residual)


def register(subparsers) -> None:
    """Add the ``complete`` sub-command to an argparse ``subparsers`` object."""
    p = subparsers.add_parser(
        "complete",
        help="replace a region (or fill a hole) with a template patch and blend the seam",
        usage="meshrepair complete IN [TEMPLATE] OUT (--region FILE | --hole K) [--mirror] "
        "[options]",
        description="Context-aware completion: remove the region of IN given by --region (or "
        "use the existing hole --hole K), align TEMPLATE (a mesh with exactly one boundary "
        "loop) to it, stitch it in and blend the seam strip with the variational model. With "
        "--mirror (IN OUT only) the template is the region's mirrored counterpart across the "
        "mesh's symmetry plane.",
    )
    p.add_argument("input", help="mesh to complete (PLY, OBJ, OFF, STL)")
    p.add_argument("paths", nargs="+", metavar="[TEMPLATE] OUT",
                   help="TEMPLATE: a template patch (a mesh file with one boundary loop; "
                   "omitted with --mirror); OUT: mesh file to write (PLY also stores m_v, "
                   "strip, template)")
    add_complete_options(p)
    p.add_argument("--log", metavar="RUN.json", default=None,
                   help="write history, parameters, timings and correspondence as JSON "
                   "(readable by 'meshrepair report --log')")
    p.add_argument("--force", action="store_true", help="overwrite OUTPUT if it exists")
    p.add_argument("--save-on-interrupt", action="store_true",
                   help="on Ctrl-C during the blend, write the current iterate instead of nothing")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    from meshrepair.commands.common import add_report_option

    add_report_option(p)
    p.set_defaults(func=run_complete)
