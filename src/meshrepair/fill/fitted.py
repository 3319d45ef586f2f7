"""The fitted-surface candidate of the patch placement (``fill_holes(fitted=True)``,
docs/holes.md section 5): the patch faired relative to a local surface fitted to its surround,
kept per hole where a probe of the surround says it predicts better."""

from __future__ import annotations

import logging

import numpy as np

from meshrepair.fill.patches import _blocks
from meshrepair.holes import fair_vertices
from meshrepair.holes.fairing import LIEPA_COT_RANGE
from meshrepair.holes.triharmonic import fair_triharmonic

log = logging.getLogger("meshrepair.fill")


def _model_fairing(curvature: bool, triharmonic: bool, cot_range):
    """The fairing kept for a hole, as a function ``(V, F, free, exclude_rows,
    curvature_exclude)``: the thin plate, followed by the triharmonic fairing when that is the
    one kept."""

    def fair(V, F, free, exclude_rows=None, curvature_exclude=None):
        Y = fair_vertices(V, F, free, order=2, weights="cotan", iterations=3,
                          exclude_rows=exclude_rows, curvature=curvature,
                          curvature_exclude=curvature_exclude, cot_range=cot_range)
        if triharmonic:
            ex = np.zeros(len(V), bool)
            for e_ in (exclude_rows, curvature_exclude):
                if e_ is not None:
                    ex[np.asarray(e_)] = True
            Y = fair_triharmonic(Y, F, free, iterations=3, exclude_rows=ex)
        return Y

    return fair


def _fitted_candidates(V, F, V1, Vm, F1, reports, method, on_crease, sharp_v, curvature, nV,
                       nF):
    """Per hole without crease routes: the patch faired by the thin plate relative to the local
    surface fitted to its surround (:mod:`meshrepair.holes.fitted`; the fit carries the
    curvature), kept where it predicts the surround better than the fairing kept for the hole
    (thin plate, or thin plate then triharmonic) on a probe: the hole widened by a band of
    ``j = PROBE_BAND R / l̄`` rings of the surround, both run on the widened hole (the fit
    refitted without the band), and the RMS distances of the band's faired vertices to their
    true positions compared (reason ``", fitted dD kK"``)."""
    from meshrepair.holes.fitted import (
        PROBE_BAND,
        PROBE_BAND_MAX,
        fair_on_fit,
        fit_hole,
        hole_rings,
    )

    sharp_m = np.zeros(nV, bool)
    sharp_m[sharp_v] = True
    by_rep = {r.index: r for r in reports}
    out = V1.copy()
    for i, (bv, _bf) in _blocks(reports, nV, nF).items():
        rep = by_rep[i]
        if rep.n_creases or rep.reason.startswith("annulus") or len(bv) < 3:
            continue
        d, le, R = hole_rings(F, rep.loop, nV, V)
        fit = fit_hole(V, F, d, le, nV, exclude=sharp_m)
        if fit is None:
            continue
        cot = LIEPA_COT_RANGE if method[i] == "liepa" else None
        tri = ", triharmonic" in rep.reason
        common = dict(exclude_rows=on_crease, curvature_exclude=sharp_v)
        opts = dict(common, fair=_model_fairing(curvature, False, cot))
        base = dict(common, fair=_model_fairing(curvature, tri, cot))
        start = V1.copy()
        start[bv] = Vm[bv]
        j = min(PROBE_BAND_MAX, max(2, int(round(PROBE_BAND * R / max(le, 1e-300)))))
        band = np.flatnonzero((d < j) & ~sharp_m)
        fit_p = fit_hole(V, F, d, le, nV, band=j, exclude=sharp_m)
        if fit_p is None:
            continue
        free_p = np.r_[bv, band]
        e_plain = e_fit = np.inf
        Vp = fair_on_fit(start, F1, free_p, None, **base)
        Vq = fair_on_fit(start, F1, free_p, fit_p, **opts)
        if np.isfinite(Vp[free_p]).all():
            e_plain = float(np.sqrt(((Vp[band] - V[band]) ** 2).sum(axis=1).mean()))
        if np.isfinite(Vq[free_p]).all():
            e_fit = float(np.sqrt(((Vq[band] - V[band]) ** 2).sum(axis=1).mean()))
        if not e_fit < e_plain:
            log.info("hole %d: fitted surface not kept (probe band of %d rings: %.3g vs "
                     "plain %.3g)", i, j, e_fit, e_plain)
            continue
        Vf = fair_on_fit(start, F1, bv, fit, **opts)
        if not np.isfinite(Vf[bv]).all():
            continue
        out[bv] = Vf[bv]
        rep.reason += f", fitted d{fit.degree} k{fit.rings}"
        log.info("hole %d: fitted surface kept (degree %d, %d rings)", i, fit.degree, fit.rings)
    return out
