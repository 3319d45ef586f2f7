"""``meshrepair report``: a self-contained HTML report of a repair result.

Example
-------
``meshrepair report out.ply out.html --input noisy.ply --reference truth.ply --log run.json``
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from meshrepair.commands.common import angle_degrees
from meshrepair.commands.render import check_output_path, load_mesh, reference_metrics, sharp_edges
from meshrepair.errors import MeshRepairError

#: per-vertex attributes of the result file shown as masks when they hold 0/1 values
_MASK_HINTS = ("m_v", "mask", "region", "hole", "inpaint")


def _load_log(path: str | None) -> dict:
    """Read the optional run log: a JSON list (history) or a dict with optional keys
    ``history``, ``parameters``, ``timings``, ``metrics``, ``holes`` (per-hole records)."""
    if path is None:
        return {}
    from meshrepair.io import check_input_file

    p = check_input_file(path, "--log ")
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise MeshRepairError(f"cannot read {path!r} as JSON: {exc}") from exc
    if isinstance(data, list):
        data = {"history": data}
    if not isinstance(data, dict):
        raise MeshRepairError(
            f"{path!r} must hold a JSON list of iteration records or an object with keys "
            "'history', 'parameters', 'timings', 'metrics'"
        )
    out = {}
    for key in ("history", "parameters", "timings", "metrics", "holes"):
        if key in data:
            want = list if key in ("history", "holes") else dict
            if not isinstance(data[key], want):
                raise MeshRepairError(f"'{key}' in {path!r} must be a JSON {want.__name__}")
            out[key] = data[key]
    return out


def _attribute_masks(attrs: dict, n_vertices: int) -> dict[str, np.ndarray]:
    masks = {}
    for name, a in attrs.items():
        arr = np.asarray(a).ravel()
        if arr.shape[0] != n_vertices or not any(h in name.lower() for h in _MASK_HINTS):
            continue
        if arr.dtype == bool or np.all(np.isin(arr, (0, 1))):
            masks[name] = arr.astype(bool)
    return masks


def run_report(args: argparse.Namespace) -> int:
    """Handler of ``meshrepair report``; returns the exit code."""
    from meshrepair.mesh.geometry import mean_edge_length
    from meshrepair.mesh.topology import boundary_loops
    from meshrepair.metrics import distances
    from meshrepair.report.page import write_report

    out = check_output_path(
        args.output, [args.result, args.input, args.reference, args.log], (".html", ".htm"),
        args.force,
    )
    t0 = time.perf_counter()
    res = load_mesh(args.result)
    inp = load_mesh(args.input) if args.input else None
    run = _load_log(args.log)
    timings: dict[str, float] = dict(run.get("timings", {}))

    metrics: dict[str, object] = {
        "vertices": len(res.V),
        "faces": len(res.F),
        "boundary loops": len(boundary_loops(res.F, len(res.V))),
        "mean edge length": mean_edge_length(res.V, res.F),
    }
    if inp is not None:
        metrics["input vertices"] = len(inp.V)
        metrics["input boundary loops"] = len(boundary_loops(inp.F, len(inp.V)))
    if args.reference:
        ref = load_mesh(args.reference)
        r = reference_metrics(res.V, res.F, ref.V, ref.F)
        if r is not None:
            metrics["MSAE vs reference (deg²)"] = r["MSAE"]
            metrics["E_V vs reference"] = r["E_V"]
            if inp is not None:
                r0 = reference_metrics(inp.V, inp.F, ref.V, ref.F)
                if r0 is not None:
                    metrics["input MSAE vs reference (deg²)"] = r0["MSAE"]
                    metrics["input E_V vs reference"] = r0["E_V"]
        t1 = time.perf_counter()
        d = distances(res.V, res.F, ref.V, ref.F)
        timings["report: distances to reference"] = time.perf_counter() - t1
        if d["diag"] > 0:  # a reference of zero size has distances but no relative ones
            metrics["mean surface distance / bbox diagonal"] = d["mean"] / d["diag"]
            metrics["Hausdorff distance / bbox diagonal"] = d["hausdorff"] / d["diag"]
        else:
            metrics["mean surface distance"] = d["mean"]
            metrics["Hausdorff distance"] = d["hausdorff"]
    metrics.update(run.get("metrics", {}))

    masks: dict[str, np.ndarray] = {}
    masks.update(_attribute_masks(res.vertex_attributes, len(res.V)))
    masks[f"M_E (dihedral > {args.sharp_threshold:g} deg)"] = sharp_edges(
        res.V, res.F, args.sharp_threshold
    )
    parameters = dict(run.get("parameters", {}))
    parameters.setdefault("result file", str(args.result))
    if args.input:
        parameters.setdefault("input file", str(args.input))
    if args.reference:
        parameters.setdefault("reference file", str(args.reference))
    timings["report: reading and metrics"] = time.perf_counter() - t0
    write_report(
        out,
        title=args.title or f"meshrepair report: {Path(args.result).name}",
        input_mesh=(inp.V, inp.F) if inp is not None else None,
        output_mesh=(res.V, res.F),
        masks=masks,
        metrics=metrics,
        history=run.get("history"),
        parameters=parameters,
        timings=timings,
        image_size=args.image_size,
        holes=run.get("holes"),
        output_attributes=res.vertex_attributes,
        overwrite=args.force,
    )
    print(f"wrote {out} ({time.perf_counter() - t0:.2f} s)")
    return 0


def register(subparsers) -> None:
    """Add the ``report`` sub-command to an argparse ``subparsers`` object."""
    p = subparsers.add_parser(
        "report",
        help="write a self-contained HTML report of a repair result",
        description="Write ONE offline HTML page: renders of the input and result, masks, "
        "metrics (against --reference if given), convergence plot and parameters (from --log).",
    )
    p.add_argument("result", help="repaired mesh file")
    p.add_argument("output", help="HTML file to write")
    p.add_argument("--input", default=None, help="the mesh before repair")
    p.add_argument("--reference", default=None,
                   help="ground-truth mesh: MSAE and E_V (same vertex count) and surface distances")
    p.add_argument("--log", default=None, metavar="RUN.json",
                   help="JSON run log: a list of iteration records, or an object with keys "
                   "history, parameters, timings, metrics")
    p.add_argument("--title", default=None, help="page title")
    p.add_argument("--sharp-threshold", type=angle_degrees, default=30.0, metavar="DEG",
                   help="dihedral angle for the sharp-edge mask M_E (default 30)")
    p.add_argument("--image-size", type=int, default=480, metavar="PX",
                   help="size of each rendered panel (default 480)")
    p.add_argument("--force", action="store_true", help="overwrite OUTPUT if it exists")
    p.set_defaults(func=run_report)
