"""Keep large temporary arrays on the heap during a big solve (glibc only).

glibc serves every allocation above ``M_MMAP_THRESHOLD`` (at most 32 MB) with a fresh ``mmap`` and
returns it to the kernel on ``free``. At a million vertices most per-iteration arrays (a
``(nF, 3)`` float64 array is 57 MB) are above that limit, so each ADMM iteration maps, page-faults,
zeroes and unmaps several hundred megabytes: measured on 1.18M vertices, 9.4 s of the 31.8 s of
a 10-iteration run was kernel time. Inside :func:`heap_allocations` large blocks come from the
heap and freed blocks are reused (kernel time 1.5 s, run 26.5 s; docs/performance.md).

On exit the previous limits cannot be read back from glibc, so the context restores the values
glibc's own dynamic rule converges to for such sizes (mmap threshold 32 MB, trim threshold 64 MB,
mmap enabled) and hands the free heap back to the kernel with ``malloc_trim(0)``. Elsewhere (macOS,
Windows, musl) the context does nothing.
"""

from __future__ import annotations

import ctypes
import logging
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager

log = logging.getLogger(__name__)

_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
_M_MMAP_MAX = -4
_lock = threading.Lock()
_depth = 0
_libc = None


def _glibc():
    global _libc
    if _libc is None:
        _libc = False
        if sys.platform.startswith("linux"):
            try:
                lib = ctypes.CDLL(None)
                lib.gnu_get_libc_version  # noqa: B018 - raises AttributeError if not glibc
                lib.mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
                lib.mallopt.restype = ctypes.c_int
                lib.malloc_trim.argtypes = [ctypes.c_size_t]
                _libc = lib
            except (OSError, AttributeError):  # pragma: no cover - not glibc
                _libc = False
    return _libc or None


@contextmanager
def heap_allocations(enabled: bool = True) -> Iterator[None]:
    """Serve large allocations from the (reused) heap instead of ``mmap`` while inside.

    Nested and concurrent uses are counted; the limits are restored when the last one exits.
    ``enabled=False`` (e.g. for small meshes, whose arrays are below the threshold anyway) makes
    it a no-op.
    """
    global _depth
    lib = _glibc() if enabled else None
    if lib is None:
        yield
        return
    with _lock:
        if _depth == 0:
            lib.mallopt(_M_MMAP_MAX, 0)
            lib.mallopt(_M_TRIM_THRESHOLD, 2**31 - 1)
            log.debug("large allocations served from the heap")
        _depth += 1
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0:
                lib.mallopt(_M_MMAP_THRESHOLD, 32 * 1024 * 1024)
                lib.mallopt(_M_TRIM_THRESHOLD, 64 * 1024 * 1024)
                lib.mallopt(_M_MMAP_MAX, 65536)
                lib.malloc_trim(0)
