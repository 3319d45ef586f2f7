"""PNG plot of a solver history: log energy, and log relative change (35) and residuals.

Used by the HTML report (:mod:`meshrepair.report`, which re-exports :func:`convergence_plot`);
matplotlib is imported lazily, Agg backend only.
"""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence

import numpy as np

__all__ = ["convergence_plot"]


def _is_number(v: object) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)


def _history_arrays(history: Sequence[Mapping]) -> tuple[np.ndarray, str, dict, list]:
    """x values, x label, numeric series by key and stage labels from the history dicts."""
    n = len(history)

    def num(key: str) -> np.ndarray:
        out = np.full(n, np.nan)
        for i, h in enumerate(history):
            v = h.get(key) if isinstance(h, Mapping) else None
            if _is_number(v):
                out[i] = float(v)
        return out

    it = num("iter")
    if np.all(np.isfinite(it)) and (n < 2 or np.all(np.diff(it) > 0)):
        x, xlabel = it, "iteration"
    else:
        x, xlabel = np.arange(n, dtype=np.float64), "iteration (cumulative)"
    series = {k: num(k) for k in ("energy", "rel_change", "res_t", "res_N")}
    stages = [
        str(h.get("stage")) if isinstance(h, Mapping) and h.get("stage") is not None else None
        for h in history
    ]
    return x, xlabel, series, stages


def convergence_plot(
    history: Sequence[Mapping], *, width: int = 1000, height: int = 380
) -> bytes | None:
    """PNG of the solver history: log energy and log relative change / residuals vs iteration.

    Parameters
    ----------
    history : list of dict
        One dict per iteration with any of the keys ``'iter'``, ``'energy'``, ``'rel_change'``,
        ``'res_t'``, ``'res_N'``, ``'time'``, ``'stage'``; missing or non-numeric values are
        skipped. If ``'iter'`` is missing or not increasing (e.g. restarting per stage) the
        running index is used. Changes of ``'stage'`` are marked by dashed vertical lines.
    width, height : int
        Size in pixels.

    Returns
    -------
    bytes or None
        PNG data, or None when there is nothing numeric to plot.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    if not history:
        return None
    x, xlabel, series, stages = _history_arrays(history)
    if not any(np.isfinite(v).any() for v in series.values()):
        return None
    dpi = 100
    fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi, facecolor="white")
    FigureCanvasAgg(fig)
    ax_e, ax_r = fig.subplots(1, 2)
    panels = (
        (ax_e, ("energy",), "energy"),
        (ax_r, ("rel_change", "res_t", "res_N"), "relative change / residual"),
    )
    styles = {
        "energy": ("C0", "-"),
        "rel_change": ("C1", "-"),
        "res_t": ("C2", "--"),
        "res_N": ("C3", ":"),
    }
    labels = {"res_t": "res_t", "res_N": "res_N", "rel_change": "rel. change", "energy": "energy"}
    for ax, keys, ylabel in panels:
        plotted = False
        positive_only = True
        for k in keys:
            y = series[k]
            ok = np.isfinite(y)
            if not ok.any():
                continue
            positive_only &= bool(np.all(y[ok] > 0))
            color, ls = styles[k]
            ax.plot(x[ok], y[ok], color=color, ls=ls, lw=1.4, label=labels[k],
                    marker="." if ok.sum() < 40 else None)
            plotted = True
        if not plotted:
            ax.text(0.5, 0.5, "not recorded", ha="center", va="center", transform=ax.transAxes,
                    color="#888")
            ax.set_xticks([])
            ax.set_yticks([])
            continue
        ax.set_yscale("log" if positive_only else "symlog")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.grid(True, which="major", alpha=0.3)
        if len(keys) > 1:
            ax.legend(fontsize=8, loc="best")
        _mark_stages(ax, x, stages)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, facecolor="white")
    return buf.getvalue()


def _mark_stages(ax, x: np.ndarray, stages: list) -> None:
    prev = None
    first = True
    for xi, st in zip(x, stages, strict=True):
        if st is None:
            continue
        if st != prev:
            if not first:
                ax.axvline(xi, color="#777", ls="--", lw=0.9)
            ax.annotate(st, xy=(xi, 1.0), xycoords=("data", "axes fraction"), xytext=(3, -3),
                        textcoords="offset points", va="top", fontsize=8, color="#444")
            first = False
            prev = st


