"""The run of :func:`meshrepair.denoise`: the reading and plan (:mod:`.analysis`), then its
execution (:mod:`.execute`)."""

from __future__ import annotations

from meshrepair.denoise.analysis import REORDER_MIN_VERTICES, _plan  # noqa: F401
from meshrepair.denoise.execute import _execute
from meshrepair.denoise.result import DenoiseResult
from meshrepair.model.schedule import default_stages  # noqa: F401  (re-exported)


def _denoise(V, F, *, callback=None, **options) -> DenoiseResult:
    """Plan and run in one call (the public :func:`meshrepair.denoise` without ``plan``)."""
    return _execute(_plan(V, F, digest=False, **options), V, F, callback, made_here=True)
