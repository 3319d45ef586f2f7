"""The targets on every published triple (``benchmarks/published.py``): the defaults' MSAE and
E_V at most the published research output's, and the mean angle E_a within the quality guard
of 1.1 times it (docs/parameters.md, "The published research outputs": MSAE ratios 0.42-0.96,
E_a 0.82-1.01, E_V 0.19-0.98)."""

import pytest

from meshrepair import denoise, mean_angle_error, msae, vertex_error

from .conftest import published_triple

CASES = ["gcn_fandisk_n6", "gcn_trim_star_n3", "nllr_igea", "nllr_nicolo", "nllr_pierrot",
         "tgv_fandisk", "tgv_kinect_pyramid"]


@pytest.mark.shared
@pytest.mark.parametrize("case", CASES)
def test_defaults_at_most_the_published_output(case):
    Vn, Vt, Vp, F = published_triple(case)
    r = denoise(Vn, F)
    assert msae(r.V, Vt, F) <= msae(Vp, Vt, F)
    assert mean_angle_error(r.V, Vt, F) <= 1.1 * mean_angle_error(Vp, Vt, F)
    assert vertex_error(r.V, Vt) <= vertex_error(Vp, Vt)
