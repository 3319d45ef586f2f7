"""``meshrepair fill`` and ``meshrepair inpaint``: smooth hole filling and inpainting.

Examples
--------
``meshrepair fill bunny.ply bunny_closed.ply``
``meshrepair fill scan.ply scan_filled.ply --keep-border --max-hole-size 50 --denoise``
``meshrepair fill scan.ply --list``
``meshrepair inpaint head.ply head_fixed.ply --sphere 0.1,0.2,0.3,0.05``
``meshrepair inpaint scan.ply scan_fixed.ply --sphere 0.1,0.2,0.3,0.05 --keep-border``

The output keeps what the input holds (colours, texture coordinates, materials, per-face
properties, binary/ASCII and precision; interpolated on the new vertices:
:func:`meshrepair.io.carry_attributes`); a PLY output gets a per-vertex ``filled`` property
(1 on new vertices, 0 elsewhere).
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

import numpy as np

from meshrepair.errors import MeshRepairError

log = logging.getLogger(__name__)


def _floats(text: str, n: int, what: str) -> list[float]:
    try:
        vals = [float(t) for t in text.replace(" ", "").split(",")]
    except ValueError:
        vals = []
    if len(vals) != n or not all(np.isfinite(vals)):
        raise MeshRepairError(f"{what} needs {n} comma-separated numbers, got {text!r}")
    return vals


def _write(out: Path, m, res, log_path: Path | None, extra: dict, force: bool) -> None:
    from meshrepair.commands.common import write_json_log
    from meshrepair.io import write_like_input

    write_like_input(out, m, res, extra={"filled": res.filled_mask}, force=force)
    if log_path is not None:
        data = {
            "history": res.history,
            "parameters": {k: (v if isinstance(v, (int, float, str, bool, type(None), list))
                               else str(v)) for k, v in {**res.params, **extra}.items()},
            "timings": res.timings,
            "metrics": {"holes found": len(res.holes), "holes filled": res.n_filled,
                        "holes skipped": res.n_skipped,
                        "new vertices": int(len(res.new_vertices)),
                        "new faces": int(len(res.new_faces))},
            "holes": [h.as_dict() for h in res.holes],
        }
        write_json_log(log_path, data, force=force)


def _report(args: argparse.Namespace, res, m, report_path: Path | None) -> None:
    from meshrepair.commands.common import write_run_report

    if not args.report:
        return
    from meshrepair.viewer.content import hole_regions

    highlight = np.zeros(len(res.F), bool)
    highlight[res.new_faces] = True
    regions, details = hole_regions(res.V, res.F, res.holes)
    write_run_report(
        report_path, force=args.force, title=f"meshrepair {args.command} {Path(args.input).name}",
        holes=[h.as_dict() for h in res.holes], highlight=highlight,
        highlight_label="inpainted faces" if args.command == "inpaint" else "filled faces",
        regions=regions, region_details=details, sharp_mask=res.M_E,
        input_mesh=(m.V, m.F), output_mesh=(res.V, res.F),
        masks={"filled_V": res.filled_mask, "M_E": res.M_E}, history=res.history,
        parameters=res.params, timings=res.timings,
        metrics={"holes found": len(res.holes), "holes filled": res.n_filled,
                 "holes skipped": res.n_skipped, "new vertices": int(len(res.new_vertices)),
                 "new faces": int(len(res.new_faces))})


def run_fill(args: argparse.Namespace) -> int:
    """Handler of ``meshrepair fill``; returns the exit code."""
    from meshrepair.commands.common import run_outputs
    from meshrepair.fill import fill_holes
    from meshrepair.holes import find_holes
    from meshrepair.io import read_mesh

    if args.output is None and not args.list:
        raise MeshRepairError("missing output file: give IN OUT (or --list to only list holes)")
    if args.list:
        given = [n for n, v in (("OUT", args.output), ("--report", args.report),
                                ("--log", args.log)) if v is not None]
        if given:
            raise MeshRepairError(f"--list only lists the holes and writes nothing: drop "
                                  f"{', '.join(given)}")
    paths = (None, None, None) if args.list else run_outputs(args, [args.input],
                                                              output=args.output)
    m = read_mesh(args.input)
    if args.list:
        holes = find_holes(m.V, m.F)
        print(f"{args.input}: {len(holes)} holes (longest first)")
        for h in holes:
            print(f"  hole {h.index}: {h.n_boundary} boundary edges, length {h.length:.6g}"
                  f"{', pinched' if h.pinched else ''}")
        return 0
    return _solve_and_write(args, m, paths, "fill", lambda cb, hp: fill_holes(
        m.V, m.F, **fill_options(args), callback=cb, progress=hp))


def run_inpaint(args: argparse.Namespace) -> int:
    """Handler of ``meshrepair inpaint``; returns the exit code."""
    from meshrepair.commands.common import run_outputs
    from meshrepair.fill import inpaint
    from meshrepair.fill.region import resolve_region
    from meshrepair.io import read_mesh

    paths = run_outputs(args, [args.input, args.region], output=args.output)
    m = read_mesh(args.input)
    opts = inpaint_options(args)
    region = resolve_region(opts.pop("region"), opts.pop("attribute"), len(m.V))
    return _solve_and_write(args, m, paths, "inpaint", lambda cb, hp: inpaint(
        m.V, m.F, region, **opts, callback=cb, progress=hp))


def _solve_and_write(args: argparse.Namespace, m, paths: tuple, desc: str, solve) -> int:
    """Run ``solve(callback, hole_progress)`` under progress bars (over holes, then over the
    solve's iterations; none with ``--quiet``), print the per-hole summary, write OUT (and
    ``--log``/``--report``, ``paths`` checked by ``run_outputs``); returns the exit code."""
    from meshrepair.commands.common import ProgressBar

    out, log_path, report_path = paths

    holes_bar = _HoleBar(f"{desc}: holes", enabled=not args.quiet)
    bar = None

    def iteration(entry):
        nonlocal bar
        if bar is None:
            holes_bar.close()
            bar = ProgressBar(None, desc, enabled=not args.quiet)
        bar(entry)

    try:
        res = solve(iteration, holes_bar)
    finally:
        holes_bar.close()
        if bar is not None:
            bar.close()
    if res.stop_reason == "interrupted" and not args.save_on_interrupt:
        print(f"interrupted: nothing written (pass --save-on-interrupt to keep the current "
              f"iterate of the {desc} solve)", file=sys.stderr)
        return 130
    print(res.summary())
    _write(out, m, res, log_path, {"input": args.input}, args.force)
    print(f"wrote {out} ({len(res.V)} vertices, {len(res.F)} faces, {res.timings['total']:.2f} s)")
    _report(args, res, m, report_path)
    return 0


class _HoleBar:
    """A tqdm bar over the holes being enclosed, fed by ``progress(done, total)``; created on
    the first call (so nothing is printed when no hole is filled or the input is refused)."""

    def __init__(self, desc: str, enabled: bool = True):
        self.desc, self.enabled, self.bar = desc, enabled, None

    def __call__(self, done: int, total: int) -> None:
        if not self.enabled:
            return
        if self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(total=total, desc=self.desc, unit="hole", leave=False)
        self.bar.n = done
        self.bar.refresh()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def add_solve_options(p) -> None:
    """The patch options shared by fill and inpaint (and ``meshrepair batch``)."""
    p.add_argument("--denoise", action="store_true",
                   help="also denoise the rest of the mesh in the same solve (default: only the "
                   "new vertices move)")
    p.add_argument("--initial", choices=("bilaplacian", "harmonic"), default="bilaplacian",
                   help="initial patch: curved thin-plate fairing (default) or flat membrane")
    p.add_argument("--no-refine", action="store_true",
                   help="skip the ADMM solve (keep the initial patch; ignored with --denoise)")
    p.add_argument("--fitted", action="store_true",
                   help="also try a patch faired relative to a surface fitted to the hole's "
                   "surround, kept per hole where it predicts the surround better "
                   "(docs/holes.md, section 5; off by default)")


def _solve_options(args: argparse.Namespace) -> dict:
    return dict(denoise=args.denoise, initial=args.initial, refine=not args.no_refine,
                fitted=args.fitted)


def add_fill_options(p) -> None:
    """The hole-selection options of ``meshrepair fill`` (shared with ``meshrepair batch``)."""
    p.add_argument("--max-hole-size", type=int, default=None, metavar="N",
                   help="fill only holes with at most N boundary edges")
    p.add_argument("--keep-border", action="store_true",
                   help="leave the longest loop open (the border of a scan or an open model)")
    p.add_argument("--exclude", type=int, nargs="+", default=None, metavar="I",
                   help="hole indices to leave open")
    p.add_argument("--holes", type=int, nargs="+", default=None, metavar="I",
                   help="fill only these hole indices")


def fill_options(args: argparse.Namespace) -> dict:
    """Keyword arguments of :func:`meshrepair.fill_holes` from the parsed options."""
    return dict(max_hole_size=args.max_hole_size, keep_border=args.keep_border,
                exclude=args.exclude or (), holes=args.holes, **_solve_options(args))


def add_inpaint_options(p, *, required: bool = True) -> None:
    """The region options of ``meshrepair inpaint`` (shared with ``meshrepair batch``)."""
    g = p.add_mutually_exclusive_group(required=required)
    g.add_argument("--region", metavar="FILE",
                   help="vertex mask: PLY vertex property, .npy, or a text file of indices")
    g.add_argument("--sphere", metavar="X,Y,Z,R", help="vertices within distance R of (X,Y,Z)")
    g.add_argument("--box", metavar="X0,Y0,Z0,X1,Y1,Z1", help="vertices inside the box")
    p.add_argument("--attribute", default=None,
                   help="PLY vertex property holding the mask (with --region FILE.ply)")


def inpaint_options(args: argparse.Namespace) -> dict:
    """``region`` (a mask file, or ``["sphere", [x, y, z], r]`` / ``["box", lo, hi]``),
    ``attribute`` and the keyword arguments of :func:`meshrepair.inpaint`."""
    if args.region is not None:
        region = args.region
    elif args.sphere is not None:
        x, y, z, r = _floats(args.sphere, 4, "--sphere")
        region = ["sphere", [x, y, z], r]
    elif args.box is not None:
        x0, y0, z0, x1, y1, z1 = _floats(args.box, 6, "--box")
        region = ["box", [x0, y0, z0], [x1, y1, z1]]
    else:
        region = None
    return dict(region=region, attribute=args.attribute,
                keep_border=bool(getattr(args, "keep_border", False)), **_solve_options(args))


def _common(p: argparse.ArgumentParser) -> None:
    add_solve_options(p)
    p.add_argument("--force", action="store_true", help="overwrite OUT if it exists")
    p.add_argument("--save-on-interrupt", action="store_true",
                   help="on Ctrl-C during the solve, write the current iterate instead of nothing")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    from meshrepair.commands.common import add_report_option

    add_report_option(p)
    p.add_argument("--log", default=None, metavar="RUN.json",
                   help="write the iteration history, parameters and per-hole reports as JSON "
                   "(readable by 'meshrepair report --log')")


def register(subparsers) -> None:
    """Add the ``fill`` and ``inpaint`` sub-commands to an argparse ``subparsers`` object."""
    p = subparsers.add_parser(
        "fill",
        help="fill holes smoothly (optionally denoising in the same solve)",
        description="Fill the boundary loops of a mesh with smooth patches (energy (6) with "
        "M_V = 0 on the patches). Holes are numbered longest first; list them with --list.",
    )
    p.add_argument("input", help="mesh file with holes")
    p.add_argument("output", nargs="?", default=None,
                   help="mesh file to write (PLY gets a 'filled' vertex property)")
    p.add_argument("--list", action="store_true", help="only list the holes and exit")
    add_fill_options(p)
    _common(p)
    p.set_defaults(func=run_fill)

    q = subparsers.add_parser(
        "inpaint",
        help="replace a damaged region by a smooth patch",
        description="Remove the faces touching a region and fill the hole smoothly. Kept "
        "vertices keep their order; the region's vertices are dropped; new vertices follow.",
    )
    q.add_argument("input", help="mesh file")
    q.add_argument("output", help="mesh file to write (PLY gets a 'filled' vertex property)")
    add_inpaint_options(q)
    q.add_argument("--keep-border", action="store_true",
                   help="where the region reaches an open border of the mesh, keep the faces "
                   "along the border and fill the rest (default: refuse to fill a region that "
                   "reaches an open border, which would close the border too)")
    _common(q)
    q.set_defaults(func=run_inpaint)
