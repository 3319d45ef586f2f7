"""meshrepair: feature-aware denoising, hole filling and context-aware completion of triangle
meshes with one variational model (Huska, Morigi, Recupero, JMIV 2023).

Public API::

    from meshrepair import denoise, add_noise, msae, vertex_error, read_mesh, write_mesh
    r = denoise(V, F)          # r.V, r.F, r.M_E, r.history
    r = fill_holes(V, F)       # closes holes; r.holes is a per-hole report
    r = inpaint(V, F, region)  # removes a damaged region and refills it
    r = complete(V, F, faces, (V_P, F_P))   # grafts a template patch and blends it
    out = carry_attributes(read_mesh(p), r)  # the file's colours, UVs, materials on the result
"""

import logging as _logging
import sys as _sys
import types as _types

# A library logs and never prints: without this handler Python's last-resort handler writes every
# warning of an unconfigured program to stderr. The CLI and applications configure their own
# (the records still propagate to the root logger's handlers).
_logging.getLogger("meshrepair").addHandler(_logging.NullHandler())

# The public names are imported on first use (PEP 562), so that ``import meshrepair`` (and the
# CLI's start-up, ``meshrepair --version``) does not load numba, scipy.sparse and every task;
# ``from meshrepair import X`` works for every name of ``__all__`` as before.
_LAZY = {
    "ADMMSolver": "model.solver", "SolverOptions": "model.solver",
    "SolverResult": "model.solver", "Stage": "model.solver", "StopRequested": "model.solver",
    "CompletionResult": "complete.result", "complete": "complete.api",
    "DenoiseResult": "denoise.result", "denoise": "denoise.api",
    "plan_denoise": "denoise.api", "DenoisePlan": "denoise.plan",
    "MeshRepairError": "errors",
    "FillResult": "fill", "fill_holes": "fill", "inpaint": "fill",
    "find_holes": "holes",
    "read_mesh": "io", "write_mesh": "io", "carry_attributes": "io", "write_like_input": "io",
    "distances": "metrics", "msae": "metrics", "mean_angle_error": "metrics",
    "vertex_error": "metrics", "min_face_angles": "metrics",
    "add_noise": "model.noise", "estimate_noise": "model.noise",
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

# Modules that moved into the package's wings: their old paths keep importing the same module
# object, with a DeprecationWarning naming the new path, until version 0.2.
_MOVED = {
    "solver": "model.solver", "penalties": "model.penalties", "inner": "model.inner",
    "linear": "model.linear", "priors": "model.priors", "fidelity": "model.fidelity",
    "noise": "model.noise", "relax": "model.relax", "operators": "mesh.operators",
    "geometry": "mesh.geometry", "topology": "mesh.topology", "validate": "mesh.validate",
    "array_contract": "mesh.array_contract", "framing": "render.framing",
}


class _MovedModules:
    """A meta-path finder and loader for the old paths of :data:`_MOVED`: ``import
    meshrepair.penalties`` returns ``meshrepair.model.penalties`` itself (one module object,
    so a monkeypatch or an ``isinstance`` check through either name sees the same thing)."""

    @staticmethod
    def _new(fullname: str) -> str | None:
        head, _, rest = fullname.partition(".")
        if head != __name__ or not rest:
            return None
        top, _, sub = rest.partition(".")
        new = _MOVED.get(top)
        return None if new is None else f"{__name__}.{new}" + (f".{sub}" if sub else "")

    def find_spec(self, fullname, path=None, target=None):
        if self._new(fullname) is None:
            return None
        import importlib.util

        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec):
        import importlib
        import warnings

        new = self._new(spec.name)
        warnings.warn(f"{spec.name} has moved to {new}; the old path is kept until meshrepair "
                      "0.2", DeprecationWarning, stacklevel=4)
        module = importlib.import_module(new)
        self._spec = module.__spec__
        return module

    def exec_module(self, module):
        module.__spec__ = self._spec  # the import system set the old name's spec; undo it


if not any(isinstance(f, _MovedModules) for f in _sys.meta_path):
    _sys.meta_path.insert(0, _MovedModules())

__all__ = [
    "ADMMSolver",
    "CompletionResult",
    "FillResult",
    "complete",
    "fill_holes",
    "find_holes",
    "inpaint",
    "DenoisePlan",
    "DenoiseResult",
    "MeshRepairError",
    "SolverOptions",
    "SolverResult",
    "Stage",
    "StopRequested",
    "add_noise",
    "denoise",
    "plan_denoise",
    "distances",
    "estimate_noise",
    "msae",
    "mean_angle_error",
    "read_mesh",
    "carry_attributes",
    "vertex_error",
    "min_face_angles",
    "write_like_input",
    "write_mesh",
]
__version__ = "0.1.0"
