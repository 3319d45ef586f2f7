"""The option choices of context-aware completion (:func:`meshrepair.complete`), in a module of
their own so that the command line's parser lists them without importing the task itself (which
loads numba and scipy: ``meshrepair --version`` measured 0.39 s of CPU with it,
docs/performance.md)."""

MODES = ("smooth", "sharp", "adaptive")
"""How the blended seam treats creases (``--mode``)."""

ORIENTATIONS = ("template", "auto")
"""Where the template's orientation comes from (``--orientation``)."""

ICP_MODES = ("auto", "context", "boundary", "surface", "none")
"""Rigid refinement of the template placement (``--icp``, :mod:`meshrepair.complete.alignment`)."""
