"""meshrepair: feature-aware denoising, hole filling and context-aware completion of triangle
meshes with one variational model (Huska, Morigi, Recupero, JMIV 2023).

Public API::

    from meshrepair import denoise, add_noise, msae, vertex_error, read_mesh, write_mesh
    r = denoise(V, F)          # r.V, r.F, r.M_E, r.history
    r = fill_holes(V, F)       # closes holes; r.holes is a per-hole report
    r = inpaint(V, F, region)  # removes a damaged region and refills it
    r = complete(V, F, faces, (V_P, F_P))   # grafts a template patch and blends it
"""

import sys as _sys
import types as _types

# The public names are imported on first use (PEP 562), so that ``import meshrepair`` (and the
# CLI's start-up, ``meshrepair --version``) does not load numba, scipy.sparse and every task;
# ``from meshrepair import X`` works for every name of ``__all__`` as before.
_LAZY = {
    "ADMMSolver": "solver", "SolverOptions": "solver", "SolverResult": "solver",
    "Stage": "solver", "StopRequested": "solver",
    "CompletionResult": "complete", "complete": "complete",
    "DenoiseResult": "denoise", "denoise": "denoise",
    "MeshRepairError": "errors",
    "FillResult": "fill", "fill_holes": "fill", "inpaint": "fill",
    "find_holes": "holes",
    "read_mesh": "io", "write_mesh": "io",
    "distances": "metrics", "msae": "metrics", "mean_angle_error": "metrics",
    "vertex_error": "metrics",
    "add_noise": "noise", "estimate_noise": "noise",
}


def __getattr__(name: str):
    mod = _LAZY.get(name)
    if mod is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(f".{mod}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY))


class _Package(_types.ModuleType):
    """The package module: importing the submodules ``denoise`` and ``complete`` must not
    replace the public functions of the same name (as the eager ``from .denoise import denoise``
    did, the function wins)."""

    def __setattr__(self, name, value):
        if name in ("denoise", "complete") and isinstance(value, _types.ModuleType):
            return
        super().__setattr__(name, value)


_sys.modules[__name__].__class__ = _Package

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
    "mean_angle_error",
    "read_mesh",
    "vertex_error",
    "write_mesh",
]
__version__ = "0.1.0"
