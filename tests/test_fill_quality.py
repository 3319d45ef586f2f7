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


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_noise_around_the_hole_is_not_read_as_curvature(seed):
    """On a sphere with noise of 0.2 mean edge lengths the default fill still continues the
    sphere: the ratio reads the shape's curvature (|H| low-passed over 3 rings), near 1, and
    the fill is not flagged (the magnitude of the raw |H| read 0.30-0.34 and flagged it)."""
    import meshrepair as mr

    s = trimesh.creation.icosphere(4)
    V, F = np.asarray(s.vertices), np.asarray(s.faces)
    Vc, Fc = cut_holes(mr.add_noise(V, F, 0.2, seed=seed), F, 8, n_holes=1, seed=seed)[:2]
    q = fill_holes(Vc, Fc).holes[0].quality
    assert 0.8 < q["curvature_ratio"] < 1.4 and not q["check"], q


def test_low_pass_keeps_the_sides_of_the_seam_apart():
    from meshrepair.fill.quality import _low_passed

    # a path 0-1-2-3: vertices 0, 1 original, 2, 3 new; the seam edge 1-2 is not averaged over
    edges = np.array([[0, 1], [1, 2], [2, 3]])
    H = np.array([1.0, 3.0, 10.0, 20.0])
    np.testing.assert_allclose(_low_passed(H, edges, 2, 1), [3.0, 1.0, 20.0, 10.0])
    np.testing.assert_allclose(_low_passed(H, edges, 2, 2), H)


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
