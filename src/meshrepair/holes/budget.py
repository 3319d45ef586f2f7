"""Resource guards of hole filling: patch sizes estimated before any work.

The planar patch of a loop of length ``L`` has at most the area ``L² / 4π`` (isoperimetric
inequality); meshed with equilateral triangles of side ``h`` it has about
``L² / (4π · (√3/4) h²)`` triangles. :func:`estimate_patch_faces` returns that bound; fill_holes
and inpaint refuse (:class:`~meshrepair.errors.MeshRepairError`, with the count) selections whose
total exceeds :data:`MAX_NEW_FACES`, before building anything: an ``edge_length`` of 1e-4 on a
unit-size mesh asks for tens of millions of triangles and runs out of memory.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.holes.detect import Hole

MAX_NEW_FACES = 2_000_000
"""Largest number of new faces (estimated) fill_holes / inpaint agree to create in one call
(about 1.5 GB for the fairing and the solve)."""


def estimate_patch_faces(hole: Hole, h: float | None) -> int:
    """Upper estimate of the faces of the patch of ``hole`` at edge length ``h`` (default: the
    loop's mean edge length)."""
    hh = hole.length / hole.n_boundary if h is None else float(h)
    if not hh > 0:
        return 0
    area = hole.length ** 2 / (4.0 * np.pi)
    return int(area / (np.sqrt(3.0) / 4.0 * hh * hh)) + hole.n_boundary


def check_budget(holes: Iterable[Hole], h: float | None, *, what: str = "fill_holes",
                 limit: int = MAX_NEW_FACES) -> int:
    """Raise when the selected holes would create more than ``limit`` faces; return the total."""
    holes = list(holes)
    per = [estimate_patch_faces(x, h) for x in holes]
    total = int(sum(per))
    if total > limit:
        worst = int(np.argmax(per))
        hint = ("use a larger edge_length (default: each loop's own mean edge length)"
                if h is not None else "select fewer or smaller holes (max_hole_size, exclude)")
        raise MeshRepairError(
            f"{what}: the selected holes would need about {total:,} new triangles (hole "
            f"{holes[worst].index}: about {per[worst]:,} for {holes[worst].n_boundary} boundary "
            f"edges, length {holes[worst].length:.4g}"
            + (f", edge_length {h:.3g}" if h is not None else "")
            + f"); the limit is {limit:,}: {hint}")
    return total


def _finite(name: str, val, *, lo: float | None = None, lo_open: bool = False,
            hi: float | None = None, hi_open: bool = False, allow_none: bool = False) -> None:
    if val is None and allow_none:
        return
    try:
        x = float(val)
    except (TypeError, ValueError):
        raise MeshRepairError(f"{name} must be a number, got {val!r}") from None
    ok = np.isfinite(x) and not isinstance(val, bool)
    if ok and lo is not None:
        ok = x > lo if lo_open else x >= lo
    if ok and hi is not None:
        ok = x < hi if hi_open else x <= hi
    if not ok:
        rng = []
        if lo is not None:
            rng.append(f"{'>' if lo_open else '>='} {lo:g}")
        if hi is not None:
            rng.append(f"{'<' if hi_open else '<='} {hi:g}")
        raise MeshRepairError(f"{name} must be a finite number{' ' if rng else ''}"
                              f"{' and '.join(rng)}, got {val!r}")


def _integer(name: str, val, lo: int, hi: int | None = None) -> None:
    if isinstance(val, (bool, np.bool_)) or not isinstance(val, (int, np.integer, float)) \
            or not np.isfinite(val) or int(val) != val or val < lo \
            or (hi is not None and val > hi):
        rule = f">= {lo}" if hi is None else f"in [{lo}, {hi}]"
        raise MeshRepairError(f"{name} must be an integer {rule}, got {val!r}")


def check_fill_options(*, edge_length, lam, th, a, max_iter, tol, rings, relax,
                       inner_iters) -> None:
    """Validate the numeric options of fill_holes / inpaint (finite, in range), naming the
    option in the message."""
    _finite("edge_length", edge_length, lo=0.0, lo_open=True, allow_none=True)
    _finite("lam", lam, lo=0.0, lo_open=True, allow_none=True)
    _finite("th", th, lo=0.0, lo_open=True, hi=180.0, hi_open=True)
    _finite("a", a, lo=0.0, lo_open=True)
    _finite("tol", tol, lo=0.0)
    _finite("relax", relax, lo=0.0)
    from meshrepair.options import MAX_INNER_ITERATIONS, MAX_ITERATIONS

    _integer("max_iter", max_iter, 0, MAX_ITERATIONS)
    _integer("rings", rings, 1)
    _integer("inner_iters", inner_iters, 1, MAX_INNER_ITERATIONS)
