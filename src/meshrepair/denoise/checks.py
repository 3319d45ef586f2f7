"""The options of a denoise call, checked (finite, in range) before any work on the mesh."""

from __future__ import annotations

from meshrepair.model.solver import SolverOptions


def _checked(lam, th, a, robust_iters, feature_iters, mask_update_every, min_feature_edges, tol,
             unfold, inner_solver, inner_iters, n_solver, stages, huber_delta, willmore_weight,
             regions, polish) -> dict:
    """Every option checked (finite, in range) before any work on the mesh."""
    from meshrepair.options import (
        MAX_INNER_ITERATIONS,
        MAX_ITERATIONS,
        check_angle,
        check_bool,
        check_int,
        check_number,
    )

    o = dict(
        lam=check_number("lam", lam, low=0, allow_none=True),
        th=check_angle("th", th),
        a=check_number("a", a, low=0, low_open=True),
        robust_iters=check_int("robust_iters", robust_iters, low=0, high=MAX_ITERATIONS,
                               allow_none=True),
        feature_iters=check_int("feature_iters", feature_iters, low=0, high=MAX_ITERATIONS),
        mask_update_every=check_int("mask_update_every", mask_update_every, low=0),
        min_feature_edges=check_int("min_feature_edges", min_feature_edges, low=1),
        inner_iters=check_int("inner_iters", inner_iters, low=1, high=MAX_INNER_ITERATIONS,
                              allow_none=True),
        tol=check_number("tol", tol, low=0, low_open=True),
        unfold=check_bool("unfold", unfold),
        inner_solver=inner_solver,
        n_solver=n_solver,
        stages=None if stages is None else tuple(stages),
        huber_delta=check_number("huber_delta", huber_delta, low=0, low_open=True,
                                 allow_none=True),
        willmore_weight=check_number("willmore_weight", willmore_weight, low=0, low_open=True,
                                     allow_none=True),
        regions=check_bool("regions", regions),
        polish=check_bool("polish", polish),
    )
    SolverOptions(th=th, tol=o["tol"], inner_solver=inner_solver,
                  inner_iters=3 if o["inner_iters"] is None else o["inner_iters"],
                  n_solver=n_solver, mask_update_every=o["mask_update_every"],
                  min_feature_edges=o["min_feature_edges"],
                  **({"stages": o["stages"]} if o["stages"] is not None else {})).validate()
    return o
