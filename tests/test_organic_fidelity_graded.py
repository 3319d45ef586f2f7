"""The data weight graded by the tangential ratio of the noise
(:func:`meshrepair.denoise.organic_fidelity.tangential_gain`)."""

from __future__ import annotations

import numpy as np
import pytest

from meshrepair import add_noise, denoise, msae
from meshrepair.denoise import organic_fidelity as of
from meshrepair.denoise.rules import TANGENTIAL_MAX
from meshrepair.denoise.scale import tangential_ratio
from meshrepair.synthetic import grid_plane

from .conftest import shared_mesh


def test_gain_is_one_up_to_ratio_one_then_grows_as_its_square():
    """g(r_t) = 1 for r_t < 0.65 and for 0.65 ≤ r_t ≤ 1, (1 + r_t²)/2 above 1 up to the largest
    trusted read (2.5, g = 3.625): continuous at 1, non-decreasing there; a read above it, and
    NaN, give 1."""
    for r in (0.0, 0.3, TANGENTIAL_MAX - 1e-9, TANGENTIAL_MAX, 0.9, 1.0, float("nan")):
        assert of.tangential_gain(r) == 1.0
    assert of.tangential_gain(1.0 + 1e-9) == pytest.approx(1.0)
    assert of.tangential_gain(2.0) == pytest.approx(2.5)
    assert of.tangential_gain(of.GAIN_RATIO_MAX) == pytest.approx(3.625)
    for r in (of.GAIN_RATIO_MAX + 1e-9, 3.0, 18.6):
        assert of.tangential_gain(r) == 1.0
    rs = np.linspace(0.0, of.GAIN_RATIO_MAX, 401)
    g = np.array([of.tangential_gain(r) for r in rs])
    assert np.all(np.diff(g) >= 0)


def test_graded_law_is_the_ungraded_law_times_the_gain():
    """λ_graded(γ̂, r_t) = max(g c/γ̂², 0.05): equal to the ungraded law wherever g = 1 (normal
    noise, r_t ≤ 1) and the low-passed cap is not reached, g times it where neither bound is
    active, uncapped; the ungraded law (the run on a low-passed input) is capped at
    LOWPASSED_LAMBDA_MAX."""
    for g in np.linspace(0.105, 1.2, 60):
        for r in (0.2, 0.7, 1.0):
            assert of.organic_lambda(g, r) == pytest.approx(of.organic_lambda(g, r, graded=False))
    r = 1.85
    gain = 0.5 * (1 + r * r)
    for g in (0.01, 0.075, 0.1, 0.2):
        assert of.organic_lambda(g, r) == pytest.approx(gain * 0.08 / g ** 2)
    assert of.organic_lambda(float("nan"), r) == pytest.approx(gain * 0.08 / 1e-3 ** 2)
    assert of.organic_lambda(0.065, r, graded=False) == pytest.approx(of.LOWPASSED_LAMBDA_MAX)
    assert of.organic_lambda(0.01, 0.2, graded=False) == pytest.approx(of.LOWPASSED_LAMBDA_MAX)


@pytest.mark.parametrize("ratio", [0.5, 1.0, 2.0])
def test_the_read_is_the_tangential_to_normal_noise_ratio(ratio):
    """The analytic case behind the gain's read: on a flat regular grid with Gaussian noise of
    standard deviation σ_n along the normal and σ_t per tangential axis, the umbrella and its
    high-pass are the same linear filter on each coordinate, so the filtered tangential part is
    a 2-D Gaussian of σ_t' = κ σ_t and the normal part has σ_n' = κ σ_n; the median of a
    χ²₂-distributed ‖R‖²/σ_t'² is 2 ln 2, hence r_t = √(ln 2) σ_t/σ_n ≈ 0.833 σ_t/σ_n
    (isotropic noise reads 0.83: ``r_t > 1`` means a tangential part 1.2× the normal one)."""
    V, F = grid_plane(70)
    rng = np.random.default_rng(11)
    sn = 0.05
    E = np.c_[ratio * sn * rng.standard_normal((len(V), 2)), sn * rng.standard_normal(len(V))]
    r = tangential_ratio(V + E, F, V)
    assert r == pytest.approx(np.sqrt(np.log(2.0)) * ratio, rel=0.06)


@pytest.mark.shared
def test_nicolo_low_random_noise_beats_the_tuned_and_default_peers():
    """docs/comparison.md's nicolo γ0.1 random (seed 1): Open3D Laplacian 35.8 tuned and at its
    defaults; measured 34.6 with the graded weight (λ 17.7 at r_t 1.85), 39.0 before it."""
    V, F = shared_mesh("nicolo.ply")
    V0 = add_noise(V, F, 0.1, direction="random", seed=1)
    r = denoise(V0, F)
    assert r.params["tangential_ratio"] > 1.0
    assert r.params["lam"] > of.LOWPASSED_LAMBDA_MAX
    assert msae(r.V, V, F) < 0.98 * 35.8


def test_reanchoring_reads_the_residual_at_the_ungraded_weight():
    """ρ_t √g: the identity at g = 1 (and for g < 1, which the gain never gives), √g times the
    ratio otherwise; main_lambda records the gain it used (1 when not graded)."""
    for r in (0.0, 0.3, 0.59):
        assert of.reanchor_ratio_at_ungraded(r, 1.0) == r
        assert of.reanchor_ratio_at_ungraded(r, 0.5) == r
    assert of.reanchor_ratio_at_ungraded(0.553, 1.345) == pytest.approx(0.553 * np.sqrt(1.345))
    info: dict = {}
    lam = of.main_lambda(0.065, 1.85, info)
    from meshrepair.denoise.rules import LAMBDA_SCALE as C_DEFAULT

    assert info["lambda_gain"] == pytest.approx(of.tangential_gain(1.85) * of.LAMBDA_SCALE
                                                / C_DEFAULT)
    assert lam == pytest.approx(of.organic_lambda(0.065, 1.85))
    lam0 = of.main_lambda(0.065, 1.85, info, graded=False)
    assert info["lambda_gain"] == 1.0 and lam0 == pytest.approx(of.LOWPASSED_LAMBDA_MAX)


@pytest.mark.shared
def test_a_graded_weight_does_not_switch_the_reanchoring_on():
    """nicolo γ0.2 random, seed 5: the organic law raises the weight by g c/c_d = 2.64 over the
    default law and the residual's tangential ratio reads 0.477 (re-anchoring there measured
    58.1); read at the default law's weight (ρ_t √2.64 = 0.78 ≥ 0.6) the re-anchoring stays off:
    measured 49.9."""
    V, F = shared_mesh("nicolo.ply")
    V0 = add_noise(V, F, 0.2, direction="random", seed=5)
    r = denoise(V0, F)
    p = r.params
    assert p["lambda_gain"] > 1.2
    assert p["reanchor_ratio"] < 0.6 <= p["reanchor_ratio"] * np.sqrt(p["lambda_gain"])
    assert p["reanchored"] == 0
    assert msae(r.V, V, F) < 52.0
