"""Worker of ``benchmarks/denoise.py --vs-meshlib``: one library on one mesh in a fresh process.

Run as::

    python benchmarks/_vs_meshlib.py --worker '{"lib": "meshrepair", "npz": "...", "warm": 3}'

The input (noisy vertices, faces, truth) is read from an ``.npz`` with numpy only, so the
library's own import is timed here: ``import_s`` (``import meshrepair`` or ``import meshlib``),
``first_s`` (the first call in the process: for meshrepair this loads the compiled kernels from
numba's cache), ``warm_s`` (minimum of ``warm`` further calls). MeshLib is
``meshDenoiseViaNormals`` with default ``DenoiseViaNormalsSettings``, the conversion to and from
its mesh type included (as a user calling it from numpy pays it). Prints ``RESULT {json}``.
"""

from __future__ import annotations

import os

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS",
           "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402


def _meshrepair():
    t = time.perf_counter()
    from meshrepair import denoise

    t_imp = time.perf_counter() - t

    def run(V, F):
        return denoise(V, F).V

    return t_imp, run


def _meshlib():
    t = time.perf_counter()
    import meshlib.mrmeshnumpy as mn
    import meshlib.mrmeshpy as mm

    t_imp = time.perf_counter() - t

    def run(V, F):
        m = mn.meshFromFacesVerts(np.ascontiguousarray(F, np.int32), np.ascontiguousarray(V))
        mm.meshDenoiseViaNormals(m, mm.DenoiseViaNormalsSettings())
        out = np.asarray(mn.getNumpyVerts(m), np.float64)
        if len(out) != len(V):  # pragma: no cover - MeshLib keeps the vertex set
            raise RuntimeError("MeshLib changed the vertex count")
        return out

    return t_imp, run


def run_worker(spec: dict) -> dict:
    from threadpoolctl import threadpool_limits

    z = np.load(spec["npz"])
    Vn, F, Vt = z["Vn"], z["F"], z["V"]
    with threadpool_limits(1):
        t_imp, run = _meshrepair() if spec["lib"] == "meshrepair" else _meshlib()
        t = time.perf_counter()
        Vo = run(Vn, F)
        first = time.perf_counter() - t
        warm = []
        for _ in range(int(spec.get("warm", 3))):
            t = time.perf_counter()
            Vo = run(Vn, F)
            warm.append(time.perf_counter() - t)
    from meshrepair import msae

    return {"lib": spec["lib"], "nV": int(len(Vn)), "import_s": t_imp, "first_s": first,
            "warm_s": float(min(warm)) if warm else float("nan"), "warm_all": warm,
            "msae_in": msae(Vn, Vt, F), "msae_out": msae(Vo, Vt, F)}


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--worker":
        print("RESULT " + json.dumps(run_worker(json.loads(sys.argv[2]))), flush=True)
    else:
        raise SystemExit(__doc__)
