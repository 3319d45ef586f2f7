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
def rng():
    return np.random.default_rng(12345)
