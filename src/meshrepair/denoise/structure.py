r"""The method-noise test of a CAD part's result: did the crease reading invent structure?

The CAD reading (crease support ``f = |C| / n_E`` of the probe at least
:data:`meshrepair.denoise.rules.CAD_SUPPORT`) switches on the stronger prior off the creases
(outside weight), the tangential anchor and the CAD finish. The probe that reads ``C`` is a
piecewise-flat solve, and on a coarse, strongly curved smooth surface under heavy noise it can
break the curvature into facets whose edges read as crease chains; the CAD model then removes
the curvature between them with the noise. The reading cannot tell such chains from a real
part's creases (their persistence, spread and contrast read alike); the result can.

**The test** is the one of :mod:`meshrepair.denoise.whiteness` (Buades, Coll and Morel's *method
noise*): the residual ``r_i = ⟨y_i − x_i, n_i⟩ / l̄`` of a denoiser that removes only white
noise has no spatial structure, and its one-ring correlation (Moran's I on the edge graph)

.. math:: ρ_1 = \frac{\sum_i r_i (W r)_i}{\sum_i r_i^2}

is at most about 0 (``(I − S) η`` of white noise ``η`` is a high-pass). A residual whose
neighbours correlate (``ρ_1 >`` :data:`~meshrepair.denoise.whiteness.RHO1_MAX`) holds signal the
model removed: curvature flattened into facets. The plan of a CAD part read on white noise
therefore carries the organic reading's plan (the same probe, the crease support read as 0) in
``if_structured``; the executor solves the CAD plan first and, when its residual fails the
test, solves the organic plan and keeps its result when that residual passes. A call so runs at
most two main solves (the discrepancy principle's lowered outside weight is then not tried:
:mod:`meshrepair.denoise.discrepancy` corrects a weight, this test the reading).

The test applies where its premise holds: white noise read (no ``if_correlated`` plan:
correlated noise leaves a correlated residual by itself), automatic ``lam`` and
``willmore_weight`` (a user's weights are the user's model), a CAD reading.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping
from dataclasses import replace

from meshrepair.denoise.plan import Decision, DenoisePlan
from meshrepair.denoise.result import DenoiseResult
from meshrepair.denoise.rules import CAD_SUPPORT

log = logging.getLogger("meshrepair.denoise.run")

STRUCTURE_TEST = True
"""Switch of the test (module docstring)."""


def applies(plan: DenoisePlan, options: Mapping) -> bool:
    """Whether ``plan`` (one noise model's, from the reading) gets the organic alternative: a
    CAD reading on white noise with automatic weights (module docstring)."""
    sf = plan.reading.get("support_fraction", float("nan"))
    return bool(STRUCTURE_TEST and plan.if_correlated is None and plan.presmooth_steps == 0
                and options.get("lam") is None and options.get("willmore_weight") is None
                and sf >= CAD_SUPPORT)


def organic_decision(sf: float) -> Decision:
    """The record of the organic alternative's one difference from the CAD plan."""
    return Decision("cad_part", False, "the organic alternative of a CAD plan: the crease "
                    f"support (read {sf:.3g} ≥ {CAD_SUPPORT:g}) is not taken as a CAD part; run "
                    "when the CAD result's residual holds structure (structure.py)",
                    {"support_fraction": sf})


def execute_structured(plan: DenoisePlan, V, F, callback, made_here: bool,
                       execute: Callable[..., DenoiseResult]) -> DenoiseResult:
    """The CAD plan, then the organic one when the CAD result's residual fails the test; the
    organic result is kept when its own residual passes (module docstring). A CAD plan the user
    edited (:func:`dataclasses.replace`) runs alone, the test recorded as off. ``execute`` runs
    one plan (:func:`meshrepair.denoise.execute._execute`)."""
    from meshrepair.denoise import discrepancy as _dq
    from meshrepair.denoise.plan import edited_fields
    from meshrepair.denoise.whiteness import RHO1_MAX, white_residual

    st = plan._state
    pc = replace(plan, if_structured=None)
    edited = edited_fields(plan)
    if edited:  # the user's own model: run as edited, and say the test is off
        r = execute(pc, V, F, callback, made_here=made_here)
        dec = Decision("structure_test", "off", "the CAD plan was edited (" + ", ".join(edited)
                       + "): run as edited, the organic plan not tried", by_user=True)
        r.plan = replace(r.plan, after_solve=r.plan.after_solve + (dec,))
        r.params["structure_test"] = "off"
        return r
    r = execute(pc, V, F, callback, made_here=made_here, resolve=False)
    t = white_residual(V, r.V, F, st.topo.edges, st.gamma)
    n_first = r.params["main_solves"]
    q = r.params["discrepancy_ratio"]
    done = r.stop_reason == "interrupted"  # a user's stop: this result is the answer
    kept, rho_org = "CAD part", float("nan")
    if not done and t.rho1 > RHO1_MAX:
        ro = execute(plan.if_structured, V, F, callback, made_here=made_here, resolve=False)
        rho_org = white_residual(V, ro.V, F, st.topo.edges, st.gamma).rho1
        log.info("structure test: the CAD result's residual reads rho1 %.3f, the organic "
                 "one's %.3f", t.rho1, rho_org)
        n_total = n_first + ro.params["main_solves"]
        if rho_org <= RHO1_MAX:
            r, kept = ro, "organic"
        r.params["main_solves"] = n_total
    elif not done and (lowered := _dq.lowered_weight(q)) is not None:
        log.info("outside weight lowered to %g (discrepancy ratio %.3f)", lowered, q)
        r = execute(pc, V, F, callback, made_here=made_here, outside=lowered)
        r.params["main_solves"] += n_first
    r.params["discrepancy_ratio"] = q
    dec = Decision("structure_test", kept, "method-noise test of the CAD result's residual "
                   f"(one-ring correlation ρ₁ > {RHO1_MAX:g}: the organic plan runs, kept when "
                   "its residual passes; structure.py)",
                   {"rho1_cad": t.rho1, "rho1_organic": rho_org})
    r.plan = replace(r.plan, after_solve=r.plan.after_solve + (dec,))
    r.params.update(structure_test=kept, structure_rho1_cad=t.rho1,
                    structure_rho1_organic=rho_org)
    return r
