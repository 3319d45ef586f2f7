"""Render one triangle mesh to an RGB image: :func:`render_mesh`."""

from __future__ import annotations

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.render.camera import _aim, _box_corners, _view_window
from meshrepair.render.checks import (
    _check_bounds,
    _check_mesh,
    _check_shading,
    _face_highlight,
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
from meshrepair.render.raster import _raster, _to_uint8

MAX_RASTER_PIXELS = 4096 * 4096
"""Largest ``width * height * supersample**2`` :func:`render_mesh` accepts. Measured peak memory
is about 150 bytes per raster pixel at 3000 x 3000 (depth, face ids, colour, the matplotlib
figure), so the limit is about 2.3 GiB."""
_BYTES_PER_RASTER_PIXEL = 150


def check_raster(width, height, supersample=1, *, panels: int = 1,
                 min_size: int = 16) -> tuple[int, int, int]:
    """``(width, height, supersample)`` checked: whole numbers, at least ``min_size`` pixels a
    side, supersample 1-4, and ``panels`` such images within :data:`MAX_RASTER_PIXELS` raster
    pixels (refused before any work, with the memory it would take)."""
    from meshrepair.options import check_int

    width, height = check_int("width", width), check_int("height", height)
    supersample = check_int("supersample", supersample)
    if width < min_size or height < min_size:
        raise MeshRepairError(f"image size must be at least {min_size} x {min_size} pixels, got "
                              f"{width} x {height}")
    if supersample < 1 or supersample > 4:
        raise MeshRepairError(f"supersample must be 1, 2, 3 or 4, got {supersample}")
    raster = int(panels) * width * height * supersample**2
    if raster > MAX_RASTER_PIXELS:
        what = f"{panels} panels of " if panels > 1 else "image "
        raise MeshRepairError(
            f"{what}{width} x {height} with supersample {supersample} is {raster:,} raster "
            f"pixels (about {raster * _BYTES_PER_RASTER_PIXEL / 2**30:.1f} GiB); the limit is "
            f"{MAX_RASTER_PIXELS:,}: choose a smaller size")
    return width, height, supersample


def render_mesh(
    V: np.ndarray,
    F: np.ndarray,
    *,
    scalars: np.ndarray | None = None,
    color_by: str | None = None,
    shading: str = "flat",
    edge_mask: np.ndarray | None = None,
    region_mask: np.ndarray | None = None,
    azimuth: float | None = None,
    elevation: float | None = None,
    width: int = 800,
    height: int = 800,
    clip_percentile: tuple[float, float] = (2.0, 98.0),
    vmin: float | None = None,
    vmax: float | None = None,
    cmap: str | None = None,
    colorbar: bool = True,
    title: str | None = None,
    fit_bounds: np.ndarray | None = None,
    supersample: int = 1,
    colorbar_label: str | None = None,
    view_dir: np.ndarray | None = None,
    look_at: np.ndarray | None = None,
    radius: float | None = None,
    clip: bool = True,
    categorical: bool | None = None,
) -> np.ndarray:
    """Render a triangle mesh to an RGB image (headless, white background).

    Parameters
    ----------
    V : (nV, 3) float
        Vertex positions.
    F : (nF, 3) int
        Triangles.
    scalars : (nV,) or (nF,) float, optional
        Per-vertex (interpolated across faces) or per-face values to colour by; an array that
        has both lengths is taken per vertex. NaN values are drawn grey.
    color_by : {"curvature", "none", "scalars"}, optional
        ``"curvature"``: signed discrete mean curvature
        (:func:`meshrepair.mesh.operators.mean_curvature`) on a diverging colour map with a range
        symmetric about 0; ``"none"``: uniform light grey; ``"scalars"``: ``scalars``.
        Default: ``"scalars"`` if ``scalars`` is given, else ``"curvature"``.
    shading : {"flat", "smooth"}
        Lambert head-light shading with per-face normals or per-pixel interpolated vertex
        normals.
    edge_mask : (nE,) bool, optional
        Edges to draw as dark lines, aligned with
        ``meshrepair.mesh.topology.edge_topology(F).edges`` (numeric 0/1 masks are accepted).
        Hidden edges are not drawn.
    region_mask : (nV,) or (nF,) bool, optional
        Per-vertex mask (faces whose three vertices are inside are tinted blue) or per-face mask
        (those faces are tinted). An array with both lengths is taken per vertex.
    azimuth, elevation : float, optional
        Camera angles in degrees (rotation about ``+y``, tilt towards ``+y``; ``0, 0`` looks
        from ``+z`` with ``+y`` up; one given, the other is 0). With neither angle nor
        ``view_dir`` the camera shows the object's front with its up vertical
        (:func:`meshrepair.render.autocam.default_view`: from its principal axes and the side
        its faces look at; deterministic, independent of the vertex order). The orthographic
        view is always fitted to the projected mesh (or to ``fit_bounds``).
    width, height : int
        Size of the returned image in pixels (title and colour bar included).
    clip_percentile : (lo, hi)
        Percentiles of the values giving the automatic colour range (robust to outliers).
    vmin, vmax : float, optional
        Explicit colour range; overrides ``clip_percentile`` for the bound(s) given.
    cmap : str, optional
        Matplotlib colour-map name; default ``"coolwarm"`` for curvature, ``"viridis"`` else.
    colorbar : bool
        Draw a colour bar at the right (ignored for ``color_by="none"``).
    title : str, optional
        Text above the picture.
    fit_bounds : (2, 3) float, optional
        ``[min_xyz, max_xyz]`` box the camera is fitted to (default: the mesh's bounding box);
        pass the same box to render several meshes from the same camera.
    supersample : int
        Render at ``supersample`` times the resolution and average down (anti-aliasing; costs
        ``supersample**2`` times the raster time).
    colorbar_label : str, optional
        Label of the colour bar (default "mean curvature" for curvature colouring).
    view_dir : (3,) float, optional
        Direction the camera looks in (instead of ``azimuth``/``elevation``). Up on the
        picture is the object's up (:func:`meshrepair.render.autocam.object_up`), or, when
        looking along it, that of :func:`meshrepair.render.framing.view_axes`.
    look_at : (3,) float, optional
        Point at the centre of the picture; the view is fitted to the sphere of ``radius``
        around it instead of the whole mesh (aim at a region with
        :func:`meshrepair.render.framing.frame_faces` /
        :func:`~meshrepair.render.framing.frame_hole`).
    radius : float, optional
        Radius of that sphere (required with ``look_at``, > 0).
    clip : bool
        With ``look_at``: clip away the geometry between the camera and the sphere, so a region
        inside a cavity or behind another part is visible.
    categorical : bool, optional
        Colour ``scalars`` by category (one flat colour per distinct value, no interpolation,
        a colour bar with one box per value). Default: automatic for ``color_by="scalars"``
        when the finite values are at most 12 distinct integers (e.g. a 0/1 mask) and no
        ``vmin``/``vmax`` is given.

    Returns
    -------
    (height, width, 3) uint8
        RGB image.

    Raises
    ------
    MeshRepairError
        For malformed meshes, masks or options.
    """
    V, F = _check_mesh(V, F)
    from meshrepair.options import check_number

    width, height, supersample = check_raster(width, height, supersample)
    azimuth = check_number("azimuth", azimuth, allow_none=True)
    elevation = check_number("elevation", elevation, allow_none=True)
    _check_shading(shading)
    mode = _resolve_color_mode(color_by, scalars)
    values = _scalar_field(V, F, mode, scalars)
    lo, hi = _value_range(values, mode, clip_percentile, vmin, vmax)
    cats = _categories(values, mode, categorical, vmin, vmax, cmap)
    cmap = cmap or ("coolwarm" if mode == "curvature" else "viridis")
    _lut(cmap)  # validate early
    em = _selected_edges(F, len(V), edge_mask)
    hl = _face_highlight(F, len(V), region_mask)
    axes, window, near = _aim(azimuth, elevation, view_dir, look_at, radius, clip, V, F)
    if window is None:
        fit_pts = V if fit_bounds is None else _box_corners(_check_bounds(fit_bounds))
        window = _view_window(fit_pts, axes)
    elif fit_bounds is not None:
        raise MeshRepairError("pass either look_at/radius or fit_bounds, not both")
    draw_cb = colorbar and values is not None
    dpi = 100.0
    fs = _font_pt(width, height)
    cb_w = _colorbar_width(fs, dpi) if draw_cb else 0
    title_h = int(round(2.4 * fs * dpi / 72.0)) if title else 0
    vw, vh = width - cb_w, height - title_h
    if vw < 16 or vh < 16:
        raise MeshRepairError(
            f"image {width} x {height} is too small for the title/colour bar; enlarge it or pass "
            "colorbar=False, title=None"
        )
    img = _raster(
        V, F, values=values, vmin=lo, vmax=hi, cmap=cmap, shading=shading, edges=em,
        face_highlight=hl, axes=axes, window=window, width=vw, height=vh,
        supersample=supersample, near=near, categories=cats,
    )  # fmt: skip
    raster = _to_uint8(img)
    if not draw_cb and not title:
        return raster
    fig = _new_figure(width, height, dpi)
    fig.figimage(raster, xo=0, yo=0, origin="upper")
    if title:
        fig.text(
            0.5 * vw / width, 1.0 - 0.5 * title_h / height, title,
            ha="center", va="center", fontsize=fs * 1.1,
        )  # fmt: skip
    if draw_cb:
        _panel_colorbar(
            fig, vw + 4, 0, vh, width, height, lo, hi, cmap, colorbar_label, mode, fs, dpi, cats
        )
    return _figure_to_array(fig)

