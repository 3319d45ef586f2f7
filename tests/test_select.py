"""meshrepair._kernels.select.median is np.median's value exactly (one selection instead of numpy's
two-index partition), and the MAD of meshrepair.denoise.scale built on it too."""

import numpy as np
import pytest

from meshrepair._kernels.select import median, median_inplace
from meshrepair.denoise.scale import _mad_std


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 8, 9, 100, 101, 4610, 23050, 23051])
def test_median_is_numpy_median(n, rng):
    for x in (rng.normal(size=n), rng.integers(0, 3, size=n).astype(float),  # ties
              np.sort(rng.normal(size=n)), -np.sort(rng.normal(size=n)), np.full(n, 2.5)):
        ref = np.median(x)
        keep = x.copy()
        assert median(x) == ref
        assert np.array_equal(x, keep)  # median leaves its input alone
        y = x.copy()
        assert median_inplace(y) == ref and np.array_equal(np.sort(y), np.sort(x))


def test_median_of_2d_and_empty(rng):
    X = rng.normal(size=(37, 4))
    assert median(X) == np.median(X)
    assert np.isnan(median(np.zeros(0)))


@pytest.mark.parametrize("overwrite", [False, True])
def test_mad_std_is_the_numpy_formula(overwrite, rng):
    X = rng.standard_t(3, size=(5001, 3))
    x = X.ravel()
    ref = float(1.4826 * np.median(np.abs(x - np.median(x))))
    keep = X.copy()
    assert _mad_std(X, overwrite=overwrite) == ref
    if not overwrite:
        assert np.array_equal(X, keep)
