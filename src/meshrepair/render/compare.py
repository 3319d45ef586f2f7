"""Paper-style comparison figures: several meshes side by side, one camera, one colour range."""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.render.camera import _aim, _view_window
from meshrepair.render.checks import (
    _check_mesh,
    _check_shading,
    _face_highlight,
    _per_mesh,
    _selected_edges,
)
from meshrepair.render.colour import (
    _categories,
    _lut,
    _resolve_color_mode,
    _scalar_field,
    _value_range,
)
from meshrepair.render.figure import (
    _colorbar_width,
    _figure_to_array,
    _font_pt,
    _new_figure,
    _panel_colorbar,
)
from meshrepair.render.mesh import check_raster
from meshrepair.render.png import save_png
from meshrepair.render.raster import _raster, _to_uint8


def compare_figure(
    meshes: Sequence[tuple[np.ndarray, np.ndarray]],
    titles: Sequence[str] | None = None,
    *,
    metrics: Sequence[str] | None = None,
    out_path: str | os.PathLike | None = None,
    fit: str = "union",
    overwrite: bool = True,
    **render_kw,
) -> np.ndarray:
    """Paper-style comparison: several meshes in one row, same camera, one colour range.

    Parameters
    ----------
    meshes : list of (V (nV_i, 3), F (nF_i, 3))
    titles : list of str, optional
        One title per mesh, drawn above its panel.
    metrics : list of str, optional
        One text per mesh (may contain newlines), drawn below its panel.
    out_path : path, optional
        Where to save the PNG.
    overwrite : bool
        If False, refuse to replace an existing ``out_path``.
    fit : {"union", "first"}
        Fit the common camera to the union of all bounding boxes or to the first mesh's.
    **render_kw
        Options of :func:`render_mesh`. ``width``/``height`` are the size of *one* panel
        (default 600 x 600); ``scalars`` may be a list with one array per mesh. The colour range
        is computed once from all meshes' values (robust percentiles) unless ``vmin``/``vmax``
        are given; ``edge_mask``/``region_mask`` may be lists with one entry (or None) per mesh.
        ``view_dir``/``look_at``/``radius``/``clip`` aim the one camera of all panels.

    Returns
    -------
    (H, W, 3) uint8
        The figure; ``W`` is ``n * width`` plus the colour bar.
    """
    n = len(meshes)
    if n == 0:
        raise MeshRepairError("compare_figure needs at least one mesh")
    checked = [_check_mesh(V, F) for V, F in meshes]
    for name, seq in (("titles", titles), ("metrics", metrics)):
        if seq is not None and len(seq) != n:
            raise MeshRepairError(f"{name} has {len(seq)} entries for {n} meshes; give one each")
    kw = dict(render_kw)
    for bad in ("title", "fit_bounds"):
        if bad in kw:
            raise MeshRepairError(f"compare_figure sets {bad} itself; do not pass it")
    width, height = kw.pop("width", 600), kw.pop("height", 600)
    colorbar = bool(kw.pop("colorbar", True))
    clip = tuple(kw.pop("clip_percentile", (2.0, 98.0)))
    vmin, vmax = kw.pop("vmin", None), kw.pop("vmax", None)
    shading = kw.pop("shading", "flat")
    _check_shading(shading)
    # every panel and the figure that holds them side by side within the raster limit
    width, height, supersample = check_raster(width, height, kw.pop("supersample", 1), panels=n)
    azimuth, elevation = kw.pop("azimuth", None), kw.pop("elevation", None)
    view_dir, look_at = kw.pop("view_dir", None), kw.pop("look_at", None)
    radius, clip_front = kw.pop("radius", None), bool(kw.pop("clip", True))
    categorical = kw.pop("categorical", None)
    scalars = kw.pop("scalars", None)
    edge_masks = _per_mesh(kw.pop("edge_mask", None), n, "edge_mask")
    region_masks = _per_mesh(kw.pop("region_mask", None), n, "region_mask")
    label = kw.pop("colorbar_label", None)
    cmap = kw.pop("cmap", None)
    mode = _resolve_color_mode(kw.pop("color_by", None), scalars)
    if kw:
        raise MeshRepairError(f"unknown render options for compare_figure: {sorted(kw)}")
    scal_list = _per_mesh(scalars, n, "scalars") if mode == "scalars" else [None] * n
    if fit not in ("union", "first"):
        raise MeshRepairError(f"fit must be 'union' or 'first', got {fit!r}")
    values = [_scalar_field(V, F, mode, s) for (V, F), s in zip(checked, scal_list, strict=True)]
    if values[0] is None:
        lo, hi = 0.0, 1.0
    else:
        lo, hi = _value_range(np.concatenate(values), mode, clip, vmin, vmax)
    cats = None
    if values[0] is not None:
        cats = _categories(np.concatenate(values), mode, categorical, vmin, vmax, cmap)
    cmap = cmap or ("coolwarm" if mode == "curvature" else "viridis")
    _lut(cmap)
    axes, window, near = _aim(azimuth, elevation, view_dir, look_at, radius, clip_front,
                              *checked[0])
    if window is None:
        fitted = checked if fit == "union" else checked[:1]
        wins = np.stack([_view_window(V, axes) for V, _ in fitted])
        window = np.stack([wins[:, 0].min(axis=0), wins[:, 1].max(axis=0)])
    panels = []
    for (V, F), val, em, rm in zip(checked, values, edge_masks, region_masks, strict=True):
        img = _raster(
            V, F, values=val, vmin=lo, vmax=hi, cmap=cmap, shading=shading,
            edges=_selected_edges(F, len(V), em), face_highlight=_face_highlight(F, len(V), rm),
            axes=axes, window=window, width=width, height=height, supersample=supersample,
            near=near, categories=cats,
        )  # fmt: skip
        panels.append(_to_uint8(img))
    dpi = 100.0
    fs = _font_pt(width, height)
    fs_px = fs * dpi / 72.0
    draw_cb = colorbar and values[0] is not None
    cb_w = _colorbar_width(fs, dpi) if draw_cb else 0
    title_h = int(round(2.4 * fs_px)) if titles is not None else 0
    if metrics is not None:
        n_lines = max(len(str(m).splitlines()) or 1 for m in metrics)
        metric_h = int(round((n_lines * 1.35 + 1.0) * fs_px))
    else:
        metric_h = 0
    tot_w, tot_h = n * width + cb_w, title_h + height + metric_h
    fig = _new_figure(tot_w, tot_h, dpi)
    for i, panel in enumerate(panels):
        fig.figimage(panel, xo=i * width, yo=metric_h, origin="upper")
        cx = (i + 0.5) * width / tot_w
        if titles is not None:
            fig.text(
                cx, 1.0 - 0.5 * title_h / tot_h, str(titles[i]),
                ha="center", va="center", fontsize=fs * 1.1,
            )  # fmt: skip
        if metrics is not None:
            fig.text(
                cx, (metric_h - 0.4 * fs_px) / tot_h, str(metrics[i]),
                ha="center", va="top", fontsize=fs, linespacing=1.35,
            )  # fmt: skip
    if draw_cb:
        _panel_colorbar(
            fig, n * width + 4, metric_h, height, tot_w, tot_h, lo, hi, cmap, label, mode, fs, dpi,
            cats,
        )  # fmt: skip
    img = _figure_to_array(fig)
    if out_path is not None:
        save_png(out_path, img, overwrite=overwrite)
    return img

