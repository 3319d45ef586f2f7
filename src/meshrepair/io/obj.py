"""OBJ reading and writing with a small exact numpy parser (no trimesh loader: it merges and
reorders).

``v`` and ``f`` lines are used (``a``, ``a/b``, ``a//c``, ``a/b/c`` and negative relative
indices, line continuations with ``\\``); ``vt``, ``vn``, groups, materials, lines and points
are ignored. Written as ASCII with 17 significant digits (exact float64 round trip).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from meshrepair.io.common import (
    MeshData,
    _Bad,
    _check_indices,
    _fan_triangulate,
    _parse_floats,
    _read_text,
)


def _read_obj(path: Path) -> MeshData:
    text = _read_text(path)
    if "\\\n" in text:
        text = text.replace("\\\r\n", " ").replace("\\\n", " ")
    lines = [ln.lstrip() for ln in text.splitlines()]
    v_pos = [i for i, ln in enumerate(lines) if ln.startswith(("v ", "v\t"))]
    f_pos = [i for i, ln in enumerate(lines) if ln.startswith(("f ", "f\t"))]
    if not v_pos:
        raise _Bad("no vertex ('v') lines found: not an OBJ mesh file")

    vtok = [lines[i].split("#", 1)[0].split() for i in v_pos]
    short = [k for k, t in enumerate(vtok) if len(t) < 4]
    if short:
        i = v_pos[short[0]]
        raise _Bad(f"malformed vertex at line {i + 1}: {lines[i]!r} (expected 'v x y z')")
    V = _parse_floats([t[1:4] for t in vtok], "vertex", lambda k: v_pos[k] + 1)

    ftok = [lines[i].split("#", 1)[0].split()[1:] for i in f_pos]
    counts = np.fromiter((len(t) for t in ftok), dtype=np.int64, count=len(ftok))
    if (counts < 3).any():
        k = int(np.flatnonzero(counts < 3)[0])
        raise _Bad(f"face at line {f_pos[k] + 1} has {int(counts[k])} vertices "
                   "(a face needs at least 3)")
    flat_s = [t.split("/", 1)[0] for toks in ftok for t in toks]
    try:
        idx = np.array(flat_s, dtype=np.int64)
    except ValueError:
        bounds = np.cumsum(counts)
        for j, s in enumerate(flat_s):
            try:
                int(s)
            except ValueError:
                line = f_pos[int(np.searchsorted(bounds, j, side="right"))] + 1
                raise _Bad(f"malformed face index {s!r} at line {line}") from None
        raise
    if (idx == 0).any():
        j = int(np.flatnonzero(idx == 0)[0])
        line = f_pos[int(np.searchsorted(np.cumsum(counts), j, side="right"))] + 1
        raise _Bad(f"face index 0 at line {line} (OBJ indices start at 1)")
    neg = idx < 0
    if neg.any():  # relative indices: -1 is the last vertex defined before the face line
        nv_before = np.searchsorted(np.asarray(v_pos), np.asarray(f_pos))
        nv_rep = np.repeat(nv_before, counts)
        idx = np.where(neg, nv_rep + idx, idx - 1)
        if (idx < 0).any():
            j = int(np.flatnonzero(idx < 0)[0])
            line = f_pos[int(np.searchsorted(np.cumsum(counts), j, side="right"))] + 1
            raise _Bad(f"relative face index at line {line} points before the first vertex")
    else:
        idx = idx - 1
    F = _fan_triangulate(idx, counts, str(path))
    _check_indices(F, len(V))
    return MeshData(V=V, F=F, path=path)


def _write_obj(fh: Any, V: np.ndarray, F: np.ndarray) -> None:
    fh.write(b"# written by meshrepair\n")
    if len(V):
        np.savetxt(fh, V, fmt="v %.17g %.17g %.17g")
    if len(F):
        np.savetxt(fh, F + 1, fmt="f %d %d %d")
