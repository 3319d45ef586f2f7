"""A kernel's rounding does not depend on what the process compiled before it.

numba compiles the implementation of an operator such as ``x ** 2`` once per process, with the
fast-math flags of the first kernel that uses it, and reuses it in every later kernel; a kernel
written with ``**`` then rounds differently depending on which kernels ran first (the
normalisation of the ADMM's N-update, :func:`meshrepair._kernels.admm.normalize_z`, with
``x ** 2`` differs in the last bits between a process that ran the vertex normals first and
one that did not).
The non-convex solve amplifies such differences (docs/parameters.md, Known limits), so the
kernels write powers as products (:mod:`meshrepair._kernels._jit`).
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import meshrepair

SRC = Path(meshrepair.__file__).resolve().parent


def _is_jitted(fn: ast.FunctionDef) -> bool:
    for d in fn.decorator_list:
        f = d.func if isinstance(d, ast.Call) else d
        if getattr(f, "id", getattr(f, "attr", "")) in ("njit", "jit"):
            return True
    return False


def test_no_power_operator_in_compiled_kernels():
    found = []
    for p in sorted(SRC.rglob("*.py")):
        for fn in ast.walk(ast.parse(p.read_text())):
            if isinstance(fn, ast.FunctionDef) and _is_jitted(fn):
                for n in ast.walk(fn):
                    if isinstance(n, (ast.BinOp, ast.AugAssign)) and isinstance(n.op, ast.Pow):
                        found.append(f"{p.relative_to(SRC)}:{n.lineno} {fn.name}")
    assert not found, f"write powers as products in compiled kernels: {found}"


_RUN = textwrap.dedent("""
    import hashlib, sys
    import numpy as np
    import trimesh
    import meshrepair as mr
    from meshrepair._kernels import admm, faces

    rng = np.random.default_rng(0)
    N = rng.normal(size=(500, 3))
    if sys.argv[1] == "normals-first":  # a kernel without fast-math compiles first
        faces.vertex_normals(rng.normal(size=(4, 3)), np.array([[0, 1, 2], [0, 2, 3]]))
    Nn, z = admm.normalize_z(N.copy(), N.copy(), N.copy(), 10.0)
    s = trimesh.creation.icosphere(2)
    V, F = np.asarray(s.vertices), np.asarray(s.faces)
    r = mr.denoise(mr.add_noise(V, F, 0.3, seed=3), F)
    print(hashlib.md5(Nn.tobytes() + z.tobytes() + r.V.tobytes()).hexdigest())
""")


def test_results_do_not_depend_on_the_compile_order(tmp_path):
    out = []
    for order in ("normals-first", "solver-first"):
        cache = tmp_path / order  # a fresh numba cache: every kernel compiles in this process
        cache.mkdir()
        env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), MESHREPAIR_NO_NUMBA="")
        r = subprocess.run([sys.executable, "-c", _RUN, order], env=env, capture_output=True,
                           text=True, timeout=600)
        assert r.returncode == 0, r.stderr
        out.append(r.stdout.strip())
    assert out[0] == out[1]
