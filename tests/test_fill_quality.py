"""Per-hole quality read-out (issue 28, item 3): seam angle against the surround and the
patch/surround mean-curvature ratio, in HoleReport.quality, the summary and the HTML report."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from meshrepair.fill import fill_holes
from meshrepair.synthetic import cut_holes


def _sphere_hole(r):
    s = trimesh.creation.icosphere(4)
    return cut_holes(np.asarray(s.vertices), np.asarray(s.faces), r, n_holes=1, seed=0)[:2]


@pytest.mark.parametrize("r", [4, 8])
def test_sphere_hole_seam_like_surround_and_curvature_ratio_one(r):
    """A hole in a unit sphere filled at defaults continues the sphere: the seam's dihedral
    angle is the surround's within 1° and the curvature ratio is 1 within 5 %."""
    Vc, Fc = _sphere_hole(r)
    res = fill_holes(Vc, Fc)
    q = res.holes[0].quality
    assert abs(q["seam_deg"] - q["surround_deg"]) < 1.0, q
    assert abs(q["curvature_ratio"] - 1.0) < 0.05, q
    assert not q["check"]
    assert "quality: seam" in res.summary() and "CHECK" not in res.summary()
    assert res.holes[0].as_dict()["quality"] == q


def test_flat_patch_in_a_sphere_is_flagged():
    """The flat membrane (no fairing, no solve) in the same hole: a kink at the seam and a patch
    far less curved than the sphere; both are read out and the hole is flagged."""
    Vc, Fc = _sphere_hole(8)
    q = fill_holes(Vc, Fc, initial="harmonic", refine=False).holes[0].quality
    assert q["seam_deg"] > 3 * q["surround_deg"] and q["curvature_ratio"] < 0.5, q
    assert q["check"] and "seam" in q["why"] and "curved" in q["why"]


def test_quality_in_the_html_hole_table():
    from meshrepair.report.fragments import hole_table

    Vc, Fc = _sphere_hole(4)
    res = fill_holes(Vc, Fc)
    html = hole_table([h.as_dict() for h in res.holes])
    q = res.holes[0].quality
    assert "curvature / surround" in html and f"{q['seam_deg']:.1f} ({q['surround_deg']:.1f})" \
        in html
