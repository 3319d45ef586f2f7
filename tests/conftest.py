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


@pytest.fixture
def require_shared():
    """Fail (never skip) when the shared meshes are missing: tests that need them must run."""
    if not (SHARED / "MANIFEST.md").exists():
        pytest.fail(f"shared meshes missing in {SHARED}: set MESHREPAIR_SHARED_MESHES to the "
                    "folder")


needs_meshes = pytest.mark.usefixtures("require_shared")


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
