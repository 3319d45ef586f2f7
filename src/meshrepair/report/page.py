"""A self-contained HTML report of one repair run.

:func:`write_report` writes ONE HTML file that opens offline in any browser: every picture is an
embedded ``data:image/png;base64,...`` URI, the style sheet is inline, and the interactive 3-D
viewer (:mod:`meshrepair.viewer`: three.js carried in the page as a ``data:`` module, the meshes
as base64 binary) needs no server or network. The page shows the 3-D view, a per-hole table
(fill/inpaint: filled, skipped or refused, and why), the input and output renders (same camera,
one curvature colour range), each mask drawn over the mesh it belongs to, a metrics table, a
convergence plot of the solver history (matplotlib, Agg backend) and the parameters and timings
tables. All text is HTML-escaped.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Mapping, Sequence
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.mesh.topology import edge_topology
from meshrepair.report.convergence_plot import convergence_plot
from meshrepair.report.fragments import (
    _CSS,
    _esc,
    _history_summary,
    _img,
    _png_bytes,
    _table,
    hole_table,
)

__all__ = ["convergence_plot", "write_report"]

log = logging.getLogger(__name__)


# --------------------------------------------------------------------------------------------
# helpers


def _check_pair(mesh: object, name: str) -> tuple[np.ndarray, np.ndarray]:
    try:
        V, F = mesh  # type: ignore[misc]
    except (TypeError, ValueError) as exc:
        raise MeshRepairError(f"{name} must be a (V, F) pair of arrays") from exc
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F)
    if V.ndim != 2 or V.shape[1] != 3 or F.ndim != 2 or F.shape[1] != 3 or len(F) == 0:
        raise MeshRepairError(
            f"{name} must be (V (nV, 3), F (nF, 3)) with at least one face; got shapes "
            f"{V.shape} and {F.shape}"
        )
    return V, F.astype(np.int64)


# --------------------------------------------------------------------------------------------
# masks


def _mask_kind_hint(name: str) -> str | None:
    n = name.lower()
    if n.endswith("_e") or "edge" in n:
        return "edge"
    if n.endswith("_v") or "vert" in n:
        return "vertex"
    if n.endswith("_f") or "face" in n:
        return "face"
    return None


def _match_mask(
    name: str, mask: np.ndarray, meshes: Sequence[tuple[str, np.ndarray, np.ndarray]]
) -> tuple[str, np.ndarray, np.ndarray, str]:
    """Find the mesh and element kind a mask belongs to (by length; the name breaks ties)."""
    m = np.asarray(mask).ravel()
    hint = _mask_kind_hint(name)
    options = []
    for label, V, F in meshes:
        sizes = {"vertex": len(V), "face": len(F), "edge": edge_topology(F, len(V)).n_edges}
        kinds = [k for k, n in sizes.items() if n == m.shape[0]]
        if hint in kinds:
            return label, V, F, hint
        options += [(label, V, F, k) for k in kinds]
    if options:
        return options[0]
    sizes = "; ".join(
        f"{label}: {len(V)} vertices, {len(F)} faces, {edge_topology(F, len(V)).n_edges} edges"
        for label, V, F in meshes
    )
    raise MeshRepairError(
        f"mask {name!r} has {m.shape[0]} entries, matching no element count ({sizes}); pass one "
        "value per vertex, face or edge (edges in meshrepair.mesh.topology.edge_topology order)"
    )


# --------------------------------------------------------------------------------------------
# the page


def write_report(
    path: str | os.PathLike,
    *,
    title: str,
    output_mesh: tuple[np.ndarray, np.ndarray],
    input_mesh: tuple[np.ndarray, np.ndarray] | None = None,
    masks: Mapping[str, np.ndarray] | None = None,
    metrics: Mapping[str, object] | None = None,
    history: Sequence[Mapping] | None = None,
    parameters: Mapping[str, object] | None = None,
    timings: Mapping[str, object] | None = None,
    image_size: int = 480,
    azimuth: float | None = None,
    elevation: float | None = None,
    holes: Sequence[Mapping] | None = None,
    viewer: bool = True,
    highlight: np.ndarray | None = None,
    highlight_label: str = "filled faces",
    regions: Sequence | None = None,
    region_details: Sequence[str] | None = None,
    sharp_mask: np.ndarray | None = None,
    output_attributes: Mapping[str, np.ndarray] | None = None,
    face_budget: int | None = None,
    overwrite: bool = True,
) -> Path:
    """Write a self-contained HTML report (images and the 3-D viewer embedded, no external
    files, opens offline).

    Parameters
    ----------
    path : str or path-like
        Output ``.html`` file (parent directories are created).
    title : str
        Page title.
    output_mesh : (V (nV, 3), F (nF, 3))
        The repaired mesh.
    input_mesh : (V (nV0, 3), F (nF0, 3)), optional
        The mesh before repair; rendered next to the output from the same camera with the same
        curvature colour range.
    masks : dict of str to array, optional
        E.g. ``{"M_E": (nE,) edge mask, "M_V": (nV,) vertex mask}``. Each mask is drawn over the
        mesh (output first, then input) that has as many edges, vertices or faces as it has
        entries; a name ending in ``_E``/``_V``/``_F`` settles ties. Edge masks are drawn as dark
        lines, vertex and face masks as a blue tint. Numeric masks are thresholded at 0.5.
    metrics : dict of str to number, optional
        Shown in a table (numbers with 6 significant digits).
    history : list of dict, optional
        Solver iterations (see :func:`convergence_plot`).
    parameters, timings : dict, optional
        Shown in tables; ``timings`` values are seconds.
    image_size : int
        Size in pixels of each mesh panel.
    azimuth, elevation : float, optional
        Camera angles for every render (see :func:`meshrepair.render.render_mesh`).
    holes : list of dict, optional
        Per-hole records of a fill/inpaint run (``HoleReport.as_dict()``: index, n_boundary,
        length, status, reason, n_new_vertices, n_new_faces, n_intersections), shown as a table
        saying which holes were filled, skipped or refused and why.
    viewer : bool
        Add the interactive 3-D viewer (:mod:`meshrepair.viewer`): input and output side by
        side with linked cameras.
    highlight : (nF_out,) bool, optional
        Output faces highlighted in the viewer (filled, inpainted or template faces), named
        ``highlight_label``.
    regions, region_details : list of Frame and of str, optional
        Holes/regions listed in the viewer with "go to"; default: the open holes of the input
        and the connected parts of ``highlight``.
    sharp_mask : (nE_out,) bool, optional
        ``M_E`` of the output for the viewer's sharp-edge overlay (default: dihedral > 30 deg).
    output_attributes : dict, optional
        Per-vertex values of the output offered as colourings in the viewer.
    face_budget : int, optional
        Faces per viewer pane above which a decimated copy is shown.
    overwrite : bool
        If False, refuse to replace an existing file. The page is written atomically.

    Returns
    -------
    Path
        The written file.
    """
    from meshrepair import render

    out = _check_pair(output_mesh, "output_mesh")
    inp = _check_pair(input_mesh, "input_mesh") if input_mesh is not None else None
    from meshrepair.render.mesh import check_raster

    try:  # the renders of the page are image_size² each, side by side at most two
        size = check_raster(image_size, image_size, panels=2, min_size=64)[0]
    except MeshRepairError as exc:
        raise MeshRepairError(f"image_size: {exc}") from None
    cam = {"azimuth": azimuth, "elevation": elevation}
    parts: list[str] = []

    # --- renders
    meshes = [("input", *inp)] if inp is not None else []
    meshes.append(("output", *out))
    parts.append("<h2>Meshes</h2>")
    rows = []
    for label, V, F in meshes:
        rows.append((f"{label}: vertices / faces", f"{len(V)} / {len(F)}"))
    parts.append(_table(rows, ("mesh", "size")))
    fig = render.compare_figure(
        [(V, F) for _, V, F in meshes],
        [label for label, _, _ in meshes],
        width=size, height=size, **cam,
    )  # fmt: skip
    parts.append(_img(_png_bytes(fig), "input and output renders",
                      "Discrete mean curvature, same camera and colour range."))

    # --- 3-D viewer
    if viewer:
        parts.append(_viewer_part(inp, out, highlight, highlight_label, regions, region_details,
                                  sharp_mask, output_attributes, face_budget))

    # --- holes
    if holes is not None:
        parts.append("<h2>Holes</h2>")
        parts.append(hole_table(holes))

    # --- masks
    if masks:
        parts.append("<h2>Masks</h2>")
        search = [meshes[-1]] + meshes[:-1]  # output first
        for name, mask in masks.items():
            label, V, F, kind = _match_mask(str(name), mask, search)
            m = np.asarray(mask).ravel()
            on = int(np.count_nonzero(m > 0.5) if m.dtype != bool else np.count_nonzero(m))
            kw = {"edge_mask": m} if kind == "edge" else {"region_mask": m}
            img = render.render_mesh(
                V, F, color_by="none", shading="smooth", width=size, height=size,
                colorbar=False, title=str(name), **kw, **cam,
            )  # fmt: skip
            plural = {"vertex": "vertices", "face": "faces", "edge": "edges"}[kind]
            parts.append(_img(_png_bytes(img), f"mask {name}",
                              f"{name}: {on} of {m.shape[0]} {plural} on the {label} mesh"))

    # --- metrics
    parts.append("<h2>Metrics</h2>")
    if metrics:
        parts.append(_table(list(metrics.items()), ("metric", "value")))
    else:
        parts.append('<p class="note">No metrics given.</p>')

    # --- convergence
    parts.append("<h2>Convergence</h2>")
    png = convergence_plot(list(history)) if history else None
    if png is not None:
        parts.append(_img(png, "convergence plot",
                          f"{len(history)} iterations; dashed lines mark stage switches."))
        parts.append(_history_summary(history))
    else:
        parts.append('<p class="note">No convergence history recorded.</p>')

    # --- parameters and timings
    parts.append("<h2>Parameters</h2>")
    if parameters:
        parts.append(_table(list(parameters.items()), ("parameter", "value")))
    else:
        parts.append('<p class="note">No parameters given.</p>')
    parts.append("<h2>Timings</h2>")
    if timings:
        rows = [(k, v) for k, v in timings.items()]
        parts.append(_table(rows, ("step", "seconds")))
    else:
        parts.append('<p class="note">No timings given.</p>')

    stamp = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    page = "\n".join(
        [
            "<!DOCTYPE html>",
            '<html lang="en">',
            "<head>",
            '<meta charset="utf-8">',
            f"<title>{_esc(title)}</title>",
            f"<style>\n{_CSS}\n</style>",
            "</head>",
            "<body>",
            f"<h1>{_esc(title)}</h1>",
            f'<p class="note">Generated by meshrepair on {_esc(stamp)}.</p>',
            *parts,
            "</body>",
            "</html>",
            "",
        ]
    )
    from meshrepair.atomic import atomic_write

    p = Path(path)
    with atomic_write(p, "w", overwrite=overwrite, make_parents=True) as fh:
        fh.write(page)
    log.info("wrote report %s (%.1f kB)", p, len(page) / 1024)
    return p


def _viewer_part(inp, out, highlight, highlight_label, regions, region_details, sharp_mask,
                 output_attributes, face_budget) -> str:
    from meshrepair.viewer import DEFAULT_FACE_BUDGET, viewer_section
    from meshrepair.viewer.content import mesh_pane, mesh_regions

    panes = []
    if inp is not None:
        panes.append(mesh_pane(*inp, "input"))
    hl = None
    if highlight is not None:
        hl = np.asarray(highlight).ravel()
        if hl.shape[0] != len(out[1]):
            raise MeshRepairError(f"highlight has {hl.shape[0]} entries for {len(out[1])} "
                                  "output faces")
        hl = hl.astype(bool)
    panes.append(mesh_pane(*out, "output", attributes=output_attributes, highlight=hl,
                           highlight_label=highlight_label, sharp_mask=sharp_mask))
    if regions is None:
        regions, region_details = [], []
        if inp is not None:
            r, d = mesh_regions(*inp, prefix="input ")
            regions, region_details = r, d
        r, d = mesh_regions(*out, highlight=panes[-1].highlight, prefix="output ",
                            label=panes[-1].highlight_label.replace(" faces", ""))
        regions, region_details = regions + r, region_details + d
    section = viewer_section(panes, regions, region_details=region_details,
                             face_budget=face_budget or DEFAULT_FACE_BUDGET)
    return ("<h2>3-D view</h2>\n<p class=\"note\">Input and output with linked cameras; "
            "the pictures below are fixed views of the same meshes.</p>\n" + section)
