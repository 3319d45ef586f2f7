"""meshrepair: feature-aware denoising, hole filling and context-aware completion of triangle
meshes with one variational model (Huska, Morigi, Recupero, JMIV 2023).

Public API::

    from meshrepair import denoise, add_noise, msae, vertex_error, read_mesh, write_mesh
    r = denoise(V, F)          # r.V, r.F, r.M_E, r.history
"""

from .denoise import DenoiseResult, denoise
from .errors import MeshRepairError
from .io import read_mesh, write_mesh
from .metrics import distances, msae, vertex_error
from .noise import add_noise, estimate_noise
from .solver import ADMMSolver, SolverOptions, SolverResult, Stage, StopRequested

__all__ = [
    "ADMMSolver",
    "DenoiseResult",
    "MeshRepairError",
    "SolverOptions",
    "SolverResult",
    "Stage",
    "StopRequested",
    "add_noise",
    "denoise",
    "distances",
    "estimate_noise",
    "msae",
    "read_mesh",
    "vertex_error",
    "write_mesh",
]
__version__ = "0.1.0"
