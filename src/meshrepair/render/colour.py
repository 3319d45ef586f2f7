"""Colours of the renderer: curvature or scalar values through a colour map, categories.

Categorical colouring: per-vertex values that are a few integers (a 0/1 mask, labels) are drawn
with one flat colour per value (nearest vertex, no blending) and a colour bar with one box per
value; a continuous colour bar would show a meaningless range (a sparse 0/1 mask has its 2-98 %
percentiles both at 0).
"""

from __future__ import annotations

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.mesh.operators import mean_curvature

_BASE_GREY = np.array([0.80, 0.80, 0.82])
_NAN_GREY = np.array([0.55, 0.55, 0.55])
_COLOR_MODES = ("curvature", "none", "scalars")
_MASK_COLOURS = np.array([_BASE_GREY, [0.95, 0.45, 0.10]])  # 0/1 masks: grey, orange
_MAX_CATEGORIES = 12


def _scalar_field(
    V: np.ndarray, F: np.ndarray, color_by: str, scalars: np.ndarray | None
) -> np.ndarray | None:
    """Per-vertex ``(nV,)`` or per-face ``(nF,)`` values to colour by, or None."""
    if color_by == "none":
        return None
    if color_by == "curvature":
        with np.errstate(all="ignore"):
            return mean_curvature(V, F)
    s = np.asarray(scalars, dtype=np.float64).ravel()
    if s.shape[0] not in (len(V), len(F)):
        raise MeshRepairError(
            f"scalars has {s.shape[0]} values but the mesh has {len(V)} vertices and {len(F)} "
            "faces; pass one value per vertex or one per face"
        )
    return s


def _robust_range(
    values: np.ndarray, clip_percentile: tuple[float, float], *, symmetric: bool
) -> tuple[float, float]:
    v = values[np.isfinite(values)]
    if v.size == 0:
        return -1.0, 1.0
    lo, hi = np.percentile(v, clip_percentile)
    if symmetric:
        m = max(abs(lo), abs(hi))
        lo, hi = -m, m
    if not hi > lo:
        d = max(abs(hi), 1.0) * 1e-6 if hi == 0 else abs(hi) * 0.5
        lo, hi = lo - d, hi + d
    return float(lo), float(hi)


def _resolve_color_mode(color_by: str | None, scalars: object) -> str:
    if color_by is None:
        return "scalars" if scalars is not None else "curvature"
    if color_by not in _COLOR_MODES:
        raise MeshRepairError(f"color_by must be one of {_COLOR_MODES}, got {color_by!r}")
    if color_by == "scalars" and scalars is None:
        raise MeshRepairError("color_by='scalars' needs scalars=<array of per-vertex values>")
    return color_by


def _lut(cmap: str) -> np.ndarray:
    import matplotlib

    try:
        cm = matplotlib.colormaps[cmap]
    except KeyError as exc:
        raise MeshRepairError(
            f"unknown colour map {cmap!r}; use a matplotlib name such as 'coolwarm' or 'viridis'"
        ) from exc
    return cm(np.linspace(0.0, 1.0, 256))[:, :3]



def _categories(values, mode, categorical, vmin, vmax, cmap) -> tuple | None:
    """(values (k,), colours (k, 3)) when ``values`` are to be coloured by category."""
    if values is None or mode != "scalars" or categorical is False:
        return None
    v = values[np.isfinite(values)]
    cats = np.unique(v)
    is_int = cats.size > 0 and bool(np.all(cats == np.round(cats)))
    if categorical is None:
        if not (is_int and cats.size <= _MAX_CATEGORIES) or vmin is not None or vmax is not None:
            return None
    elif cats.size > 64:
        raise MeshRepairError(
            f"categorical colouring needs at most 64 distinct values, got {cats.size}; pass "
            "categorical=False for a continuous colour map")
    if cats.size == 0:
        cats = np.array([0.0])
    if cmap is None and cats.size <= 2 and np.all(np.isin(cats, (0.0, 1.0))):
        colours = _MASK_COLOURS[cats.astype(int)]
    else:
        import matplotlib

        cm = matplotlib.colormaps[cmap or ("tab10" if cats.size <= 10 else "tab20")]
        if getattr(cm, "N", 256) >= 256:  # continuous map: sample it evenly
            colours = cm(np.linspace(0.0, 1.0, cats.size))[:, :3]
        else:
            colours = cm(np.arange(cats.size) % cm.N)[:, :3]
    return cats, np.asarray(colours, dtype=np.float64)



def _value_range(values, mode, clip_percentile, vmin, vmax) -> tuple[float, float]:
    try:
        p_lo, p_hi = (float(x) for x in clip_percentile)
    except (TypeError, ValueError) as exc:
        raise MeshRepairError("clip_percentile must be a pair (lo, hi), e.g. (2, 98)") from exc
    if not 0.0 <= p_lo < p_hi <= 100.0:
        raise MeshRepairError(
            f"clip_percentile must satisfy 0 <= lo < hi <= 100, got {tuple(clip_percentile)}"
        )
    if values is None:
        return 0.0, 1.0
    lo, hi = _robust_range(values, (p_lo, p_hi), symmetric=mode == "curvature")
    lo = lo if vmin is None else float(vmin)
    hi = hi if vmax is None else float(vmax)
    if not hi > lo:
        raise MeshRepairError(f"colour range must have vmin < vmax, got vmin={lo}, vmax={hi}")
    return lo, hi

