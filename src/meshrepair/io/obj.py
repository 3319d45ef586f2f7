"""OBJ reading and writing with a small exact numpy parser (no trimesh loader: it merges and
reorders).

``v`` and ``f`` lines are used (``a``, ``a/b``, ``a//c``, ``a/b/c`` and negative relative
indices, line continuations with ``\\``), and what they carry is kept: texture coordinates
(``vt``, per corner: :attr:`MeshData.texcoords` and :attr:`MeshData.face_texcoords`), normals
(``vn``, averaged per vertex into ``nx, ny, nz``), vertex colours (``v x y z r g b``, as
``red, green, blue``), materials (``mtllib`` names and ``usemtl`` per face; the ``.mtl`` file
is never read or touched). Groups (``g``, ``o``), smoothing groups, lines and points are not
kept (warning). Written as ASCII with 17 significant digits (exact float64 round trip).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

from meshrepair.io.attributes import FileFormat, uv_pair
from meshrepair.io.common import (
    MeshData,
    _Bad,
    _check_indices,
    _fan_triangulate,
    _parse_floats,
    _read_text,
)

logger = logging.getLogger("meshrepair.io")


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
    vattrs: dict[str, np.ndarray] = {}
    if all(len(t) in (7, 8) for t in vtok):  # 'v x y z r g b': vertex colours
        C = _parse_floats([t[4:7] for t in vtok], "vertex colour", lambda k: v_pos[k] + 1)
        vattrs = {"red": C[:, 0], "green": C[:, 1], "blue": C[:, 2]}

    ftok = [lines[i].split("#", 1)[0].split()[1:] for i in f_pos]
    counts = np.fromiter((len(t) for t in ftok), dtype=np.int64, count=len(ftok))
    if (counts < 3).any():
        k = int(np.flatnonzero(counts < 3)[0])
        raise _Bad(f"face at line {f_pos[k] + 1} has {int(counts[k])} vertices "
                   "(a face needs at least 3)")
    corners = [t.split("/") for toks in ftok for t in toks]
    idx = _indices([c[0] for c in corners], counts, f_pos, np.asarray(v_pos), "vertex")
    F = _fan_triangulate(idx, counts, str(path))
    _check_indices(F, len(V))
    tri_of = np.repeat(np.arange(len(counts)), counts - 2)

    texcoords = face_tc = face_mat = None
    vt_pos = [i for i, ln in enumerate(lines) if ln.startswith(("vt ", "vt\t"))]
    if vt_pos:
        texcoords = _parse_floats([lines[i].split("#", 1)[0].split()[1:3] for i in vt_pos],
                                  "texture coordinate", lambda k: vt_pos[k] + 1)
        if texcoords.shape[1] != 2:
            raise _Bad("a 'vt' line has fewer than 2 values")
        face_tc = _corner_column(corners, 1, counts, f_pos, np.asarray(vt_pos), len(texcoords),
                                 "texture coordinate", path)
    vn_pos = [i for i, ln in enumerate(lines) if ln.startswith(("vn ", "vn\t"))]
    if vn_pos:
        N = _parse_floats([lines[i].split("#", 1)[0].split()[1:4] for i in vn_pos], "normal",
                          lambda k: vn_pos[k] + 1)
        fn = _corner_column(corners, 2, counts, f_pos, np.asarray(vn_pos), len(N), "normal",
                            path)
        if fn is not None and (fn >= 0).all():
            acc = np.zeros((len(V), 3))
            np.add.at(acc, F.ravel(), N[fn.ravel()])
            for k, n in enumerate(("nx", "ny", "nz")):
                vattrs[n] = acc[:, k] / np.maximum(np.linalg.norm(acc, axis=1), 1e-300)
    mtllibs = [t for i in range(len(lines)) if lines[i].startswith("mtllib")
               for t in lines[i].split("#", 1)[0].split()[1:]]
    use = [(i, lines[i].split("#", 1)[0].split(None, 1)) for i, ln in enumerate(lines)
           if ln.startswith("usemtl")]
    materials: list[str] = []
    if use:
        names = [u[1].strip() if len(u) > 1 else "" for _, u in use]
        materials = list(dict.fromkeys(names))
        which = np.searchsorted(np.asarray([i for i, _ in use]), np.asarray(f_pos)) - 1
        code = np.asarray([materials.index(n) for n in names], np.int64)
        face_mat = np.where(which >= 0, code[np.maximum(which, 0)], -1)[tri_of]
    ignored = sorted({ln.split(None, 1)[0] for ln in lines
                      if ln[:2] in ("g ", "o ", "s ", "l ", "p ") or ln[:2] in ("g\t", "o\t")})
    if ignored:
        logger.warning("%s: OBJ %s lines are not kept (groups, smoothing groups, lines and "
                       "points); faces, materials, texture coordinates and normals are", path,
                       "/".join(ignored))
    return MeshData(V=V, F=F, vertex_attributes=vattrs, path=path, texcoords=texcoords,
                    face_texcoords=face_tc, face_materials=face_mat, materials=materials,
                    material_libraries=mtllibs, file_format=FileFormat(binary=False))


def _indices(tokens: list[str], counts: np.ndarray, f_pos: list[int], def_pos: np.ndarray,
             what: str) -> np.ndarray:
    """0-based indices from OBJ index tokens (1-based, or negative: relative to the last
    definition before the face line); ``def_pos`` are the lines defining the items."""
    lab = "" if what == "vertex" else what + " "
    try:
        idx = np.array(tokens, dtype=np.int64)
    except OverflowError:
        raise _Bad(f"a face {lab}index is larger than any vertex index can be (2^63 - 1)") from None
    except ValueError:
        bounds = np.cumsum(counts)
        for j, tok in enumerate(tokens):
            try:
                int(tok)
            except ValueError:
                line = f_pos[int(np.searchsorted(bounds, j, side="right"))] + 1
                raise _Bad(f"malformed face {lab}index {tok!r} at line {line}") from None
        raise
    if (idx == 0).any():
        j = int(np.flatnonzero(idx == 0)[0])
        line = f_pos[int(np.searchsorted(np.cumsum(counts), j, side="right"))] + 1
        raise _Bad(f"face {lab}index 0 at line {line} (OBJ indices start at 1)")
    neg = idx < 0
    if neg.any():  # relative indices: -1 is the last item defined before the face line
        n_before = np.searchsorted(def_pos, np.asarray(f_pos))
        idx = np.where(neg, np.repeat(n_before, counts) + idx, idx - 1)
        if (idx < 0).any():
            j = int(np.flatnonzero(idx < 0)[0])
            line = f_pos[int(np.searchsorted(np.cumsum(counts), j, side="right"))] + 1
            raise _Bad(f"relative face {lab}index at line {line} points before the first {what}")
        return idx
    return idx - 1


def _corner_column(corners: list[list[str]], k: int, counts: np.ndarray, f_pos: list[int],
                   def_pos: np.ndarray, n_items: int, what: str, path: Path
                   ) -> np.ndarray | None:
    """Per-triangle-corner indices of the ``k``-th slash field (``v/vt/vn``), -1 where a corner
    has none, fan-triangulated like the faces (warning-free: same fan as the positions)."""
    tok = [c[k] if len(c) > k else "" for c in corners]
    has = np.fromiter((t != "" for t in tok), dtype=bool, count=len(tok))
    if not has.any():
        return None
    flat = np.full(len(tok), -1, dtype=np.int64)
    if has.all():
        flat = _indices(tok, counts, f_pos, def_pos, what)
    else:
        sub = _indices([t if t else "1" for t in tok], counts, f_pos, def_pos, what)
        flat = np.where(has, sub, -1)
    if (flat >= n_items).any():
        raise _Bad(f"a face refers to {what} {int(flat.max()) + 1} but the file has {n_items}")
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    ntri = counts - 2
    first = np.repeat(starts, ntri)
    j = np.arange(int(ntri.sum())) - np.repeat(np.cumsum(ntri) - ntri, ntri) + 1
    return np.stack([flat[first], flat[first + j], flat[first + j + 1]], axis=1)


def _write_obj(fh: Any, V: np.ndarray, F: np.ndarray, *, vattrs: dict | None = None,
               like: MeshData | None = None) -> None:
    """Write OBJ: ``mtllib`` lines, ``v`` (with ``r g b`` if the vertex attributes hold
    colours, uchar ones scaled to [0, 1]), ``vt`` (the per-corner table of ``like``, else one
    per vertex from a per-vertex texture-coordinate pair), ``vn`` (one per vertex, from
    ``nx, ny, nz``), then the faces in order with a ``usemtl`` line wherever the material
    changes."""
    vattrs = vattrs or {}
    fh.write(b"# written by meshrepair\n")
    if like is not None:
        for lib in like.material_libraries:
            fh.write(f"mtllib {lib}\n".encode())
    cols = [V]
    fmt = "v %.17g %.17g %.17g"
    rgb = [vattrs.get(c) for c in ("red", "green", "blue")]
    if all(c is not None for c in rgb):
        C = np.stack([np.asarray(c, np.float64) for c in rgb], axis=1)
        kind = np.asarray(rgb[0]).dtype
        if kind.kind in "iu":
            C = C / np.iinfo(kind).max
        cols.append(C)
        fmt += " %.9g %.9g %.9g"
    if len(V):
        np.savetxt(fh, np.concatenate(cols, axis=1), fmt=fmt)
    tc = None
    if like is not None and like.texcoords is not None and like.face_texcoords is not None:
        if len(like.texcoords):
            np.savetxt(fh, like.texcoords, fmt="vt %.17g %.17g")
        tc = like.face_texcoords + 1
    else:
        pair = uv_pair(vattrs)
        if pair is not None:
            np.savetxt(fh, np.stack([np.asarray(vattrs[n], np.float64) for n in pair], 1),
                       fmt="vt %.17g %.17g")
            tc = F + 1
    has_n = all(n in vattrs for n in ("nx", "ny", "nz"))
    if has_n and len(V):
        N = np.stack([np.asarray(vattrs[n], np.float64) for n in ("nx", "ny", "nz")], 1)
        np.savetxt(fh, N, fmt="vn %.9g %.9g %.9g")
    if not len(F):
        return
    v = (F + 1).astype(str)
    corner = v
    if tc is not None:
        t = np.where(tc > 0, tc.astype(str), "")
        corner = np.char.add(np.char.add(corner, "/"), t)
    if has_n:
        sep = "/" if tc is not None else "//"
        corner = np.char.add(np.char.add(corner, sep), v)
    if tc is not None and not has_n:
        corner = np.char.rstrip(corner, "/")
    lines = np.char.add("f ", np.char.add(np.char.add(np.char.add(corner[:, 0], " "),
                        np.char.add(corner[:, 1], " ")), corner[:, 2]))
    mat = None if like is None else like.face_materials
    if mat is None or not like.materials:
        fh.write(("\n".join(lines.tolist()) + "\n").encode())
        return
    cut = np.flatnonzero(np.diff(mat)) + 1
    out = []
    for a, b in zip(np.r_[0, cut], np.r_[cut, len(F)], strict=True):
        if mat[a] >= 0:
            out.append(f"usemtl {like.materials[mat[a]]}")
        out.extend(lines[a:b].tolist())
    fh.write(("\n".join(out) + "\n").encode())
