"""Noise draws on which the re-integration from the input would put back the input's
tangential folds (fandisk, γ 0.3, random directions, seeds 4 / 7). Seed 7 used to read
impulsive through the creases' outliers of the Laplacian; with the coherent relief left out of
the impulsive test (:func:`meshrepair.model.noise.noise_statistics`) both seeds read Gaussian,
no re-integration runs, and the fold check of ``denoise_folds.reintegration_keeps`` has nothing
to catch here. Runs on the bundled fandisk (tests/data), no ../shared needed."""

from __future__ import annotations

import numpy as np
import pytest

import meshrepair
from meshrepair.denoise import folds as folds_mod
from meshrepair.mesh.topology import edge_topology
from meshrepair.metrics import msae
from meshrepair.model.relax import locally_flipped_faces

from .bundled import bundled_mesh


def _fandisk_random(seed):
    V, F = bundled_mesh("fandisk.ply")
    return V, F, meshrepair.add_noise(V, F, 0.3, direction="random", seed=seed)


@pytest.mark.parametrize("seed", [4, 7])
def test_failing_draws_within_the_other_seeds(seed):
    """The defaults on these draws: Gaussian noise read as such, no re-integration kept, MSAE
    within the range of the other seeds (≤ 30), at most two folded faces left."""
    V, F, V0 = _fandisk_random(seed)
    r = meshrepair.denoise(V0, F)
    p = r.params
    assert not p["impulsive"]
    assert p["reanchored"] > 0 and p["guidance_passes"] > 0
    assert p["reintegrate_steps"] == 0
    assert msae(r.V, V, F) <= 30.0
    assert int(locally_flipped_faces(r.V, edge_topology(F, len(V))).sum()) <= 2


def test_without_the_fold_check_nothing_changes(monkeypatch):
    """Seed 7 no longer reaches the re-integration: switching the fold check off leaves the
    result as it is."""
    V, F, V0 = _fandisk_random(7)
    r0 = meshrepair.denoise(V0, F)
    monkeypatch.setattr(folds_mod, "REINTEGRATE_FOLD_CHECK_RATIO", np.inf)
    r = meshrepair.denoise(V0, F)
    assert r.params["reintegrate_steps"] == r0.params["reintegrate_steps"] == 0
    np.testing.assert_array_equal(r.V, r0.V)


def test_reintegration_keeps_truth_table():
    """The fold check of the re-integration: below the ratio every re-integration is kept, above
    it only one that folds no more faces than its target."""
    keep = folds_mod.reintegration_keeps
    c = folds_mod.REINTEGRATE_FOLD_CHECK_RATIO
    assert keep(0.18, 81, 10)  # nllr_igea: noise along the normals, the folds are the input's
    assert keep(c, 100, 0)
    assert keep(0.31, 5, 6) and keep(0.4, 0, 0)  # thrown vertices / no fold put back
    assert not keep(0.475, 84, 0)  # fandisk γ0.3 random seed 4
    assert not keep(0.42, 1, 0)
    assert keep(float("nan"), 10, 0)  # not re-anchored: no ratio, nothing to check
