"""Figure layout of the renderer with matplotlib (Agg, no display): fonts, canvas, colour bars."""

from __future__ import annotations

import numpy as np


def _font_pt(width: int, height: int) -> float:
    return float(np.clip(min(width, height) / 56.0, 7.0, 15.0))


def _colorbar_width(fs_pt: float, dpi: float) -> int:
    fs_px = fs_pt * dpi / 72.0
    return int(round(1.2 * fs_px + 6.0 * fs_px + 12))


def _new_figure(width: int, height: int, dpi: float):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi, facecolor="white")
    FigureCanvasAgg(fig)
    return fig


def _figure_to_array(fig) -> np.ndarray:
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()


def _add_colorbar(fig, rect_px, total_w, total_h, vmin, vmax, cmap, label, fs_pt,
                  categories=None) -> None:
    import matplotlib
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import BoundaryNorm, ListedColormap, Normalize
    from matplotlib.ticker import MaxNLocator

    x, y, w, h = rect_px
    cax = fig.add_axes((x / total_w, y / total_h, w / total_w, h / total_h))
    if categories is not None:  # one box per category, labelled with its value
        cats, colours = categories
        k = len(cats)
        sm = ScalarMappable(norm=BoundaryNorm(np.arange(k + 1) - 0.5, k),
                            cmap=ListedColormap(colours))
        cb = fig.colorbar(sm, cax=cax, ticks=np.arange(k))
        cb.ax.set_yticklabels([f"{c:g}" for c in cats])
        tick_length = 0
    else:
        sm = ScalarMappable(norm=Normalize(vmin=vmin, vmax=vmax),
                            cmap=matplotlib.colormaps[cmap])
        cb = fig.colorbar(sm, cax=cax)
        cb.locator = MaxNLocator(nbins=5)
        cb.formatter = matplotlib.ticker.FormatStrFormatter("%.3g")
        cb.update_ticks()
        tick_length = 3
    cb.ax.tick_params(labelsize=fs_pt * 0.85, length=tick_length)
    if label:
        cb.set_label(label, fontsize=fs_pt * 0.85)
    cb.outline.set_linewidth(0.6)



def _panel_colorbar(fig, x, y, panel_h, total_w, total_h, vmin, vmax, cmap, label, mode, fs_pt,
                    dpi, categories) -> None:
    """Colour bar at pixel column ``x``, 70 % of the panel's height ``panel_h``, centred on the
    panel whose bottom is at pixel row ``y``; ``label`` None is the default for ``mode``."""
    if label is None:
        label = "mean curvature" if mode == "curvature" else ""
    bar_w = max(6, int(round(fs_pt * dpi / 72.0)))
    bar_h = int(0.7 * panel_h)
    _add_colorbar(
        fig, (x, y + (panel_h - bar_h) / 2, bar_w, bar_h), total_w, total_h, vmin, vmax, cmap,
        label, fs_pt, categories=categories,
    )  # fmt: skip
