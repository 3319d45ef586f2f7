"""The plan of a denoise call: what the reading of the input decided, printable and editable.

:func:`meshrepair.plan_denoise` reads the input (noise level and direction, the robust probe's
crease support, the noise's correlation across scales) and returns a frozen :class:`DenoisePlan`
without the main solve; :func:`meshrepair.denoise` with ``plan=`` executes one, so a user can
print it, change a decision with :func:`dataclasses.replace` and run it::

    p = mr.plan_denoise(V, F)
    print(p)                                   # every decision, the values read, the rule
    r = mr.denoise(V, F, plan=replace(p, lam=0.2))
    r.plan                                     # the plan that ran, with the decisions taken
                                               # after the solve

The editable decisions are the fields of :class:`DenoisePlan` below ``# decisions``; the
executor derives everything else from them (for example the per-edge Willmore weights from
``willmore_weight`` and ``outside_weight`` on the probe's crease support). The probe's arrays
travel with the plan, hidden from its printout and from comparisons, so executing a plan never
runs the probe again.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np

from meshrepair.model.solver import Stage


@dataclass(frozen=True)
class Decision:
    """One decision of the plan.

    Attributes
    ----------
    name : what is decided (a plan field, or a stage switched on or off)
    value : the outcome
    rule : the rule that decided it, one line (its function and threshold), or who set it
    reads : the measured values the rule read, by name
    by_user : True when the user's option set it (the rule did not run)
    """

    name: str
    value: Any
    rule: str
    reads: Mapping[str, float] = field(default_factory=dict)
    by_user: bool = False

    def line(self) -> str:
        reads = ", ".join(f"{k} {_fmt(v)}" for k, v in self.reads.items())
        who = "user" if self.by_user else "rule"
        return (f"{self.name:<22} {_fmt(self.value):>12}  [{who}] {self.rule}"
                + (f"  (read: {reads})" if reads else ""))


@dataclass(frozen=True)
class DenoisePlan:
    """A denoise call, decided and not yet run (see the module docstring).

    Attributes
    ----------
    n_vertices, n_faces : the input's size (the vertices some face uses: the others are not read)
    options : the user's options after their checks (``None`` where the reading decides)
    reading : the values read from the input (noise levels, direction, correlation, crease
        support), each computed once
    lam : fidelity weight λ of (6), per squared mean edge length
    huber_delta : threshold of the robust Huber fidelity (0: quadratic)
    willmore_weight : weight of edge-Willmore on the smooth edges
    outside_weight : its factor outside the crease-supported region (1: none)
    inner_iters : V-steps per ADMM iteration
    stages : the ADMM stages of the main solve
    start_from_probe : the main solve starts from the probe's result
    presmooth_steps : Taubin λ|μ pairs applied to the input before the whole model runs again
        on it (coarse-to-fine; 0: none); ``inner`` is then the plan of that low-passed input
    polish : the finishing polish rule may run
    decisions : every decision above, with what it read and the rule that made it
    if_correlated : the correlated-noise model's plan, run instead when the result of this
        (white-noise) plan fails the white-noise test (:mod:`meshrepair.denoise.whiteness`);
        ``None``: this plan's result is kept. Replace it by ``None`` to run this plan alone
    if_structured : the organic reading's plan of a CAD part, run when the result of this plan
        removes structure (its residual fails the method-noise test,
        :mod:`meshrepair.denoise.structure`); ``None``: this plan's result is kept
    after_solve : decisions the executor takes on the solve's result (filled in
        :attr:`meshrepair.DenoiseResult.plan`; empty before the run)
    """

    n_vertices: int
    n_faces: int
    options: Mapping[str, Any]
    reading: Mapping[str, float]
    # decisions
    lam: float
    huber_delta: float
    willmore_weight: float
    outside_weight: float
    inner_iters: int
    stages: tuple[Stage, ...]
    start_from_probe: bool
    presmooth_steps: int
    polish: bool
    # records
    decisions: tuple[Decision, ...] = ()
    inner: DenoisePlan | None = None
    if_correlated: DenoisePlan | None = None
    if_structured: DenoisePlan | None = None
    after_solve: tuple[Decision, ...] = ()
    _state: Any = field(default=None, repr=False, compare=False)

    def __str__(self) -> str:
        return self.explain()

    def explain(self, indent: str = "") -> str:
        """The plan as text: the reading, each decision with its rule, the stages."""
        out = [f"{indent}denoise plan: {self.n_vertices} vertices, {self.n_faces} faces"]
        if self.reading:
            out.append(f"{indent}  reading:")
            out += [f"{indent}    {k:<24} {_fmt(v)}" for k, v in self.reading.items()]
        out.append(f"{indent}  decisions:")
        out += [f"{indent}    {d.line()}" for d in decisions_with_edits(self)]
        out.append(f"{indent}  stages of the main solve:")
        for s in self.stages:
            out.append(f"{indent}    {s.name or 'stage'}: a={_fmt(s.a)} eps={_fmt(s.eps)} "
                       f"mask={s.mask} max_iter={s.max_iter}")
        if self.inner is not None:
            out.append(f"{indent}  then, on the input low-passed by {self.presmooth_steps} "
                       "Taubin pairs, the plan `inner` runs (the fields above are those of a "
                       "run on the raw input, used with presmooth_steps=0):")
            out.append(self.inner.explain(indent + "    "))
        if self.if_correlated is not None:
            out.append(f"{indent}  if the result's residual fails the white-noise test, "
                       "instead:")
            out.append(self.if_correlated.explain(indent + "    "))
        if self.if_structured is not None:
            out.append(f"{indent}  if the result's residual holds structure (method-noise "
                       "test), the organic plan, kept when its residual passes:")
            out.append(self.if_structured.explain(indent + "    "))
        if self.after_solve:
            out.append(f"{indent}  after the solve:")
            out += [f"{indent}    {d.line()}" for d in self.after_solve]
        return "\n".join(out)

    def editable(self) -> tuple[str, ...]:
        """Names of the fields a user may change with :func:`dataclasses.replace`."""
        names = [f.name for f in fields(self)]
        return tuple(names[names.index("lam"):names.index("decisions")])


def _fmt(v: Any) -> str:
    if isinstance(v, bool) or v is None:
        return str(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else f"{v:.4g}"
    return str(v)


@dataclass
class _State:
    """What the reading leaves for the executor: arrays in the solve's (possibly Morton) order
    and in input order, the probe's result, and the reading's record ``info``."""

    topo: Any
    report: Any
    gamma: float
    gamma_rms: float
    impulsive: bool
    n_unf: int
    reorder: bool
    Fw: np.ndarray
    topo_w: Any
    pf: Any
    inv: Any
    Vw: np.ndarray
    Vd: np.ndarray
    Vi: Any
    opts_kw: dict
    force: Any
    flat: Any
    anchor: Any
    sup: Any
    sup_v: Any
    r1: Any
    r1_V: Any
    info: dict
    auto_robust: bool
    auto_inner: bool
    robust_iters: int
    probe: bool
    presmoothed: bool
    mesh_key: str = ""
    presmooth: dict | None = None
    first_probe: Any = None
    lowpassed_from: Any = None  # (raw input y, pairs k_p) of a coarse-to-fine run's input
    planned: dict | None = None  # the editable fields as the reading decided them
    record: dict | None = None  # the record fields (RECORD_FIELDS) as the reading made them
    band: Any = None  # the two-octave band read (corrwhite.BandRead), where the plan made it


RECORD_FIELDS = ("options", "reading", "decisions")
"""Fields of a plan that record how it was made: they are read, not edited (an edit would not
change what runs)."""


def planned_values(plan: DenoisePlan) -> dict:
    """The values of ``plan``'s editable fields (:meth:`DenoisePlan.editable`) but
    ``presmooth_steps``, by name: what :func:`edited_fields` compares against."""
    return {k: getattr(plan, k) for k in plan.editable() if k != "presmooth_steps"}


def edited_fields(plan: DenoisePlan) -> list[str]:
    """The editable fields of ``plan`` (but ``presmooth_steps``) whose value differs from the
    one the reading decided: the user's edits (:func:`dataclasses.replace`). Empty for a plan
    that carries no reading."""
    st = plan._state
    if st is None or st.planned is None:
        return []
    return [k for k, v in st.planned.items() if getattr(plan, k) != v]


def decisions_with_edits(plan: DenoisePlan) -> tuple[Decision, ...]:
    """``plan.decisions`` with each field the user edited (:func:`edited_fields`) recorded as
    what runs: its current value, set by the user."""
    edited = set(edited_fields(plan))
    return tuple(Decision(d.name, getattr(plan, d.name), "edited by the user "
                          "(dataclasses.replace)", by_user=True) if d.name in edited else d
                 for d in plan.decisions)


def as_record(plan: DenoisePlan, **changes) -> DenoisePlan:
    """The record of ``plan`` after its run (``DenoiseResult.plan``): the user's edits in its
    decisions, no reading state (it would hold the probe's arrays alive), ``changes``."""
    return replace(plan, decisions=decisions_with_edits(plan), _state=None, **changes)


def mesh_key(V: np.ndarray, F: np.ndarray) -> str:
    """A digest of the arrays a plan reads: a plan runs only on the mesh it was made from."""
    import hashlib

    h = hashlib.blake2b(digest_size=16)
    h.update(np.ascontiguousarray(V, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(F, dtype=np.int64).tobytes())
    return h.hexdigest()
