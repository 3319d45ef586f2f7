import os
from pathlib import Path

import numpy as np
import pytest

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"
SHARED = Path(os.environ.get("MESHREPAIR_SHARED_MESHES", SHARED))


def shared_mesh(name: str):
    """Read a mesh from ../shared/meshes (the real meshes with provenance)."""
    from meshrepair.io import read_mesh

    p = SHARED / name
    if not p.exists():
        pytest.fail(f"shared mesh {p} is missing: set MESHREPAIR_SHARED_MESHES to the folder")
    m = read_mesh(p)
    return m.V, m.F


def published_triple(case: str):
    """``(V_noisy, V_truth, V_published, F)`` of a triple in ../shared/meshes/published (same
    vertex order and faces in all three)."""
    Vn, F = shared_mesh(f"published/{case}__noisy.ply")
    Vt, _ = shared_mesh(f"published/{case}__truth.ply")
    Vp, _ = shared_mesh(f"published/{case}__published.ply")
    return Vn, Vt, Vp, F


@pytest.fixture
def require_shared():
    """Fail (never skip) when the shared meshes are missing: tests that need them must run."""
    if not (SHARED / "MANIFEST.md").exists():
        pytest.fail(f"shared meshes missing in {SHARED}: set MESHREPAIR_SHARED_MESHES to the "
                    "folder")


needs_meshes = pytest.mark.usefixtures("require_shared")

# Markers that select tests needing more than a clone of the project:
#   shared  - reads the real meshes in ../shared/meshes (turn on with --shared)
#   browser - drives the system Chromium (turn on with --browser)
# They are deselected by default (pytest reports them as deselected, never as passed); when
# turned on and their data or browser is missing they fail, never skip.
OPT_IN_MARKERS = {"shared": "--shared", "browser": "--browser"}


def pytest_addoption(parser):
    parser.addoption("--shared", action="store_true",
                     help="also run the quality tests that read ../shared/meshes")
    parser.addoption("--browser", action="store_true",
                     help="also run the browser tests (system Chromium)")


def pytest_collection_modifyitems(config, items):
    keep, drop = [], []
    for item in items:
        # a test that needs the shared meshes is a shared test, marked or not
        if "require_shared" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.shared)
        off = [m for m, opt in OPT_IN_MARKERS.items()
               if item.get_closest_marker(m) is not None and not config.getoption(opt)]
        (drop if off else keep).append(item)
    if drop:
        config.hook.pytest_deselected(items=drop)
        items[:] = keep


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


def grid(n: int, z=None) -> tuple[np.ndarray, np.ndarray]:
    """(n x n)-vertex grid in the plane (or the graph of ``z(x, y)``), upward normals."""
    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float), indexing="ij")
    x, y = x.ravel(), y.ravel()
    V = np.c_[x, y, np.zeros(n * n) if z is None else z(x, y)]
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a = (i * n + j).ravel()
    b, c, d = a + n, a + n + 1, a + 1
    return V, np.r_[np.c_[a, b, c], np.c_[a, c, d]].astype(np.int64)

