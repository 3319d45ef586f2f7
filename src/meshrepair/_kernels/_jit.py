"""numba detection (``MESHREPAIR_NO_NUMBA=1`` turns it off), the cached :func:`njit` and the
fast-math flags shared by the kernel modules of :mod:`meshrepair._kernels`."""

from __future__ import annotations

import os

try:  # pragma: no cover - exercised through both paths in tests
    if os.environ.get("MESHREPAIR_NO_NUMBA", "") not in ("", "0"):
        raise ImportError
    from numba import njit as _numba_njit

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover
    HAVE_NUMBA = False

CACHE_DISABLED: list[str] = []
"""Kernels compiled without numba's on-disk cache (no writable cache location was found)."""


def njit(**options):
    """``numba.njit(**options)``; with ``cache=True`` the compiled kernel is kept in numba's
    on-disk cache (``__pycache__`` beside this file, else the user cache directory, else
    ``NUMBA_CACHE_DIR``), so a new process loads it instead of compiling it again (~1.5 ms per
    kernel instead of seconds). Where none of these is writable, numba refuses ``cache=True`` at
    import; the kernel is then compiled in each process instead (logged once)."""
    def deco(fn):
        if not options.get("cache"):
            return _numba_njit(**options)(fn)
        try:
            return _numba_njit(**options)(fn)
        except RuntimeError as exc:  # "cannot cache function ...: no locator available"
            if "cannot cache" not in str(exc):
                raise
            if not CACHE_DISABLED:
                import logging

                logging.getLogger(__name__).warning(
                    "numba found no writable cache directory (%s); compiled kernels are not "
                    "cached: each new process compiles them again. Set NUMBA_CACHE_DIR to a "
                    "writable directory to avoid this.", exc)
            CACHE_DISABLED.append(fn.__name__)
            return _numba_njit(**dict(options, cache=False))(fn)
    return deco

FASTMATH = {"contract", "arcp", "nsz", "reassoc"}
"""LLVM fast-math flags of the hot-loop kernels: fused multiply-add, reciprocals, reassociated
sums (vectorised reductions). Not ``nnan``/``ninf``: inputs are validated finite, and comparisons
stay IEEE. Results differ from the numpy twins by rounding only (tests/test_kernels.py); the
V-gradient kernel measured 15 % faster on a 6.5k-vertex mesh (141 vs 165 µs); the PCG kernels
4 % slower, so they keep strict IEEE arithmetic.

Kernels write powers as products (``x * x``, never ``x ** 2``; tests/test_kernel_determinism.py):
numba compiles the implementation of ``**`` once per process and reuses it in every kernel,
with the fast-math flags of the first kernel that used it, so a kernel's rounding would depend
on which kernels the process compiled before it; the non-convex solve amplifies last-bit
differences to percents of MSAE on its knife-edge rows (docs/parameters.md, Known limits)."""
