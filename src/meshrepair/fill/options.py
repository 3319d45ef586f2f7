"""The options shared by :func:`meshrepair.fill.fill_holes` and :func:`meshrepair.fill.inpaint`:
which they are, and their checks."""

from __future__ import annotations

from collections.abc import Mapping

from meshrepair.errors import MeshRepairError
from meshrepair.holes.budget import check_fill_options

INITIAL_MODES = ("bilaplacian", "harmonic")

SOLVE_OPTIONS: tuple[str, ...] = (
    "denoise", "initial", "refine", "edge_length", "lam", "th", "a", "max_iter", "tol", "rings",
    "relax", "inner_solver", "inner_iters", "check", "callback", "progress", "creases",
    "curvature", "triharmonic", "fitted")
"""Keyword parameters of both :func:`meshrepair.fill.fill_holes` and
:func:`meshrepair.fill.inpaint` that are passed on unchanged to the shared solve
(:func:`meshrepair.fill.core._fill_core`)."""


def _solve_options(params: Mapping[str, object]) -> dict:
    """The :data:`SOLVE_OPTIONS` out of ``params`` (the caller's ``locals()`` on entry)."""
    return {k: params[k] for k in SOLVE_OPTIONS}


def _check_options(opts: dict) -> dict:
    """Check the solve options (:class:`MeshRepairError` naming the bad one); returns them with
    ``max_iter`` and ``rings`` as ``int``."""
    from meshrepair.model.inner import INNER_SOLVERS
    from meshrepair.options import check_bool, check_callable, check_choice

    for k in ("denoise", "refine", "check", "creases", "curvature", "triharmonic", "fitted"):
        check_bool(k, opts[k])
    check_choice("inner_solver", opts["inner_solver"], INNER_SOLVERS)
    for k in ("callback", "progress"):
        check_callable(k, opts[k])
    initial = opts["initial"]
    if initial not in INITIAL_MODES:
        raise MeshRepairError(f"initial must be one of {INITIAL_MODES}, got {initial!r}")
    if opts["fitted"] and initial != "bilaplacian":  # the fitted fairing refines that patch
        raise MeshRepairError(f"fitted=True (--fitted) needs initial='bilaplacian', got "
                              f"initial={initial!r}: drop one of them")
    check_fill_options(**{k: opts[k] for k in ("edge_length", "lam", "th", "a", "max_iter", "tol",
                                                "rings", "relax", "inner_iters")})
    return {**opts, "max_iter": int(opts["max_iter"]), "rings": int(opts["rings"])}


ENCLOSE_ORDER: tuple[str, ...] = ("auto", "liepa")
"""Enclosing methods (:func:`meshrepair.holes.enclose_loop`) in the order they are tried on a
hole: the next one when the patch of the previous one intersects the surface both faired and
unfaired. ``"auto"``: planar projection + membrane; ``"liepa"``: Liepa's minimum-weight
triangulation refined on its own surface (loops up to :data:`meshrepair.holes.LIEPA_MAX_LOOP`
vertices). Planar first: Liepa first was less accurate after fairing on the smooth benchmark
cases (docs/holes.md, section 8)."""
