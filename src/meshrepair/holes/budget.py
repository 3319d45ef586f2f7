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


def check_fill_options(*, edge_length, lam, th, a, max_iter, tol, rings, relax,
                       inner_iters) -> None:
    """Validate the numeric options of fill_holes / inpaint (finite, in range), naming the
    option in the message (the package's option checks, :mod:`meshrepair.options`)."""
    from meshrepair.options import (
        MAX_INNER_ITERATIONS,
        MAX_ITERATIONS,
        check_angle,
        check_int,
        check_number,
    )

    check_number("edge_length", edge_length, low=0, low_open=True, allow_none=True)
    check_number("lam", lam, low=0, low_open=True, allow_none=True)
    check_angle("th", th)
    check_number("a", a, low=0, low_open=True)
    check_number("tol", tol, low=0)
    check_number("relax", relax, low=0)
    check_int("max_iter", max_iter, low=0, high=MAX_ITERATIONS)
    check_int("rings", rings, low=1)
    check_int("inner_iters", inner_iters, low=1, high=MAX_INNER_ITERATIONS)
