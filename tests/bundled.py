"""Small meshes bundled under tests/data (attribution in tests/data/ATTRIBUTION.md).

Unit tests read meshes from here so that ``pytest -q`` runs on a fresh clone; tests that need
the large shared meshes use ``conftest.shared_mesh`` and are marked ``@pytest.mark.shared``.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

DATA = Path(__file__).resolve().parent / "data"


def data_path(name: str) -> Path:
    """Path of a bundled test mesh (``fandisk.ply``, ``spot.ply``, ``trim_star.ply``) or, for
    ``fandisk_noisy.ply``, of the published noisy fandisk shipped with the package's demo."""
    if name == "fandisk_noisy.ply":
        return Path(str(files("meshrepair") / "data" / name))
    return DATA / name


def bundled_mesh(name: str):
    """``(V, F)`` of a bundled test mesh (see :func:`data_path`)."""
    from meshrepair.io import read_mesh

    m = read_mesh(data_path(name))
    return m.V, m.F
