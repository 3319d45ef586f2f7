"""Per-vertex masks read from a PLY property, a ``.npy`` array or a list of vertex indices:
:func:`read_vertex_mask`."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.io.common import PathLike, _Bad, _fail_read, _read_text, _suffix, check_input_file
from meshrepair.io.ply import _load_ply, _ply_scalar_props

# vertex properties that are never taken as a mask when no name is given
_NOT_A_MASK = {"nx", "ny", "nz", "red", "green", "blue", "alpha", "r", "g", "b", "a",
               "s", "t", "u", "v", "texture_u", "texture_v", "intensity"}


def _mask_from_values(vals: np.ndarray, n_vertices: int, source: str) -> np.ndarray:
    """Bool mask from a per-vertex 0/1 array or from a list of vertex indices."""
    vals = np.asarray(vals)
    if vals.ndim == 0:
        raise MeshRepairError(f"{source}: expected a per-vertex mask or a list of vertex "
                              f"indices, got the single value {vals.item()!r} (for one vertex, "
                              "give a list of one index)")
    if vals.ndim == 2 and 1 in vals.shape:
        vals = vals.ravel()
    if vals.ndim > 1:
        raise MeshRepairError(f"{source}: expected a 1-D mask or index list, got shape "
                              f"{vals.shape}")
    if vals.dtype == bool:
        if vals.shape[0] != n_vertices:
            raise MeshRepairError(
                f"{source}: boolean mask has {vals.shape[0]} values but the mesh has "
                f"{n_vertices} vertices (wrong length)"
            )
        return vals.copy()
    if not (np.issubdtype(vals.dtype, np.integer) or np.issubdtype(vals.dtype, np.floating)):
        raise MeshRepairError(f"{source}: expected numbers, got dtype {vals.dtype}")
    if vals.size and not np.isfinite(vals).all():
        raise MeshRepairError(f"{source}: contains NaN or infinite values")
    if vals.shape[0] == n_vertices and np.isin(vals, (0, 1)).all():
        return vals != 0  # a per-vertex 0/1 mask
    if vals.size and (vals != np.round(vals)).any():
        raise MeshRepairError(
            f"{source}: values are neither a per-vertex 0/1 mask of length {n_vertices} nor "
            "integer vertex indices"
        )
    idx = vals.astype(np.int64)
    bad = (idx < 0) | (idx >= n_vertices)
    if bad.any():
        raise MeshRepairError(
            f"{source}: {int(bad.sum())} vertex indices out of range [0, {n_vertices - 1}] "
            f"(e.g. {idx[bad][:5].tolist()})"
        )
    mask = np.zeros(n_vertices, dtype=bool)
    mask[idx] = True
    return mask


def read_vertex_mask(
    path_or_array: PathLike | np.ndarray,
    n_vertices: int,
    *,
    attribute: str | None = None,
) -> np.ndarray:
    """Read a per-vertex boolean mask (e.g. the region ``M_V`` marks).

    Accepted sources:

    * a ``.ply`` file: the vertex property ``attribute``, or else the first scalar vertex
      property other than ``x, y, z`` and the usual normal / colour / texture names; its values
      must be 0/1 (True where non-zero);
    * a ``.npy`` file or an array: a boolean array of length ``n_vertices``; a numeric array of
      length ``n_vertices`` holding only 0 and 1 (a 0/1 mask); otherwise integer vertex indices;
    * any other file: whitespace-separated integer vertex indices (``#`` comments allowed),
      interpreted like a numeric array (a file of exactly ``n_vertices`` 0/1 values is a mask).

    Parameters
    ----------
    path_or_array : str, os.PathLike or array_like
    n_vertices : int
        Number of vertices of the mesh the mask belongs to.
    attribute : str, optional
        PLY vertex property holding the mask.

    Returns
    -------
    (n_vertices,) bool ndarray
        True for listed / non-zero vertices.

    Raises
    ------
    MeshRepairError
        Missing or unreadable file, wrong length, indices out of range, non-0/1 values.
    """
    n_vertices = int(n_vertices)
    if n_vertices < 0:
        raise MeshRepairError(f"n_vertices must be >= 0, got {n_vertices}")
    if not isinstance(path_or_array, (str, os.PathLike)):
        try:
            arr = np.asarray(path_or_array)
        except Exception as exc:
            raise MeshRepairError(f"cannot use {type(path_or_array).__name__} as a vertex "
                                  f"mask ({exc})") from None
        return _mask_from_values(arr, n_vertices, "vertex mask")

    p = Path(path_or_array)
    src = f"vertex mask '{p}'"
    check_input_file(p)
    ext = _suffix(p)
    if ext == ".ply":
        try:
            ply = _load_ply(p)
        except _Bad as exc:
            raise _fail_read(p, str(exc)) from None
        if "vertex" not in [e.name for e in ply.elements]:
            raise _fail_read(p, "no 'vertex' element")
        vert = ply["vertex"]
        names = [q.name for q in _ply_scalar_props(vert)]
        if attribute is None:
            cands = [n for n in names if n not in ("x", "y", "z") and n not in _NOT_A_MASK]
            if not cands:
                raise MeshRepairError(
                    f"{src}: no mask property found among vertex properties {names}; name one "
                    "with attribute=..."
                )
            attribute = cands[0]
        elif attribute not in names:
            raise MeshRepairError(f"{src}: no vertex property {attribute!r} (has {names})")
        vals = np.array(vert.data[attribute])
        del ply
        if vals.shape[0] != n_vertices:
            raise MeshRepairError(
                f"{src}: property {attribute!r} has {vals.shape[0]} values but the mesh has "
                f"{n_vertices} vertices (wrong length)"
            )
        if not np.isin(vals, (0, 1)).all():
            raise MeshRepairError(
                f"{src}: property {attribute!r} has values other than 0 and 1 (e.g. "
                f"{vals[~np.isin(vals, (0, 1))][:3].tolist()}); threshold it first"
            )
        return vals != 0
    if ext == ".npy":
        try:
            arr = np.load(p, allow_pickle=False)
        except (ValueError, OSError, EOFError) as exc:
            raise _fail_read(p, f"not a valid .npy array ({exc})") from None
        return _mask_from_values(arr, n_vertices, src)
    try:
        text = _read_text(p)
    except _Bad as exc:
        raise _fail_read(p, str(exc)) from None
    except OSError as exc:
        raise _fail_read(p, exc.strerror or str(exc)) from None
    tokens = " ".join(ln.split("#", 1)[0] for ln in text.splitlines()).split()
    try:
        vals = np.array(tokens, dtype=np.int64)
    except OverflowError:
        raise _fail_read(p, "a vertex index is larger than any can be (2^63 - 1)") from None
    except ValueError:
        bad = next(t for t in tokens if not t.lstrip("+-").isdigit())
        raise _fail_read(p, f"expected integer vertex indices, found {bad!r}") from None
    return _mask_from_values(vals, n_vertices, src)


def read_face_selection(path: str | Path, n_faces: int) -> np.ndarray:
    """Face indices from a text file (whitespace/comma separated integers, ``#`` comments).

    Returns
    -------
    (k,) int64, sorted unique face indices in ``[0, n_faces)``
    """
    p = check_input_file(path, "region ")
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise MeshRepairError(f"cannot read region file {str(p)!r} as text: {exc}") from None
    toks = [t for line in text.splitlines()
            for t in line.split("#", 1)[0].replace(",", " ").split()]
    try:
        idx = np.array([int(t) for t in toks], dtype=np.int64)
    except OverflowError:
        raise MeshRepairError(f"region file {str(p)!r}: a face index is larger than any can be "
                              f"(2^63 - 1); the mesh has {n_faces} faces") from None
    except ValueError:
        raise MeshRepairError(f"region file {str(p)!r} must hold integer face indices (or give a "
                              ".ply/.npy per-vertex mask instead)") from None
    if idx.size == 0:
        raise MeshRepairError(f"region file {str(p)!r} lists no face")
    bad = (idx < 0) | (idx >= n_faces)
    if bad.any():
        raise MeshRepairError(f"region file {str(p)!r}: {int(bad.sum())} face indices out of range "
                              f"[0, {n_faces - 1}] (e.g. {idx[bad][:5].tolist()})")
    return np.unique(idx)
