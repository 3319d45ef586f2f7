"""meshrepair: feature-aware denoising, hole filling and context-aware completion of triangle
meshes with one variational model (Huska, Morigi, Recupero, JMIV 2023).

Public API::

    from meshrepair import denoise, add_noise, msae, vertex_error, read_mesh, write_mesh
    r = denoise(V, F)          # r.V, r.F, r.M_E, r.history
    r = fill_holes(V, F)       # closes holes; r.holes is a per-hole report
    r = inpaint(V, F, region)  # removes a damaged region and refills it
    r = complete(V, F, faces, (V_P, F_P))   # grafts a template patch and blends it
"""

from .complete import CompletionResult, complete
from .denoise import DenoiseResult, denoise
from .errors import MeshRepairError
from .fill import FillResult, fill_holes, inpaint
from .holes import find_holes
from .io import read_mesh, write_mesh
from .metrics import distances, msae, vertex_error
from .noise import add_noise, estimate_noise
from .solver import ADMMSolver, SolverOptions, SolverResult, Stage, StopRequested

__all__ = [
    "ADMMSolver",
    "CompletionResult",
    "FillResult",
    "complete",
    "fill_holes",
    "find_holes",
    "inpaint",
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
