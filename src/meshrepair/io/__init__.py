"""Reading and writing triangle meshes (PLY, OBJ, OFF, STL) without altering them.

Readers keep the vertex order and the face list exactly as stored in the file: nothing is
merged, reordered, re-oriented or removed (unreferenced vertices stay). Two exceptions, both
logged:

* polygons with more than 3 vertices (OBJ, OFF, PLY) are fan-triangulated in place,
  ``[a, b, c, d] -> [a, b, c], [a, c, d]`` (warning with the count);
* STL stores an unconnected triangle soup, so exactly equal corner positions are merged into
  one vertex (``-0.0`` equals ``0.0``), vertices numbered in order of first appearance (info).

PLY is read with :mod:`plyfile` (ASCII and binary, any byte order); extra per-vertex scalar
properties (e.g. a mask, colours, quality) are returned in :attr:`MeshData.vertex_attributes`.
OBJ, OFF and STL use small exact numpy parsers (no trimesh loaders: they merge and reorder).

Writers produce binary little-endian PLY (``double x, y, z``, faces ``uchar`` count + ``int``
indices, one property per vertex attribute), ASCII PLY, OBJ and OFF (17 significant digits, so
float64 values round-trip exactly) and binary or ASCII STL (binary STL stores float32: a warning
is logged when coordinates lose precision). Files are written to a temporary file in the target
directory and then renamed, so a failed write never leaves a truncated mesh behind.

Every failure raises :class:`~meshrepair.errors.MeshRepairError` naming the file and the problem.

Modules (one per format, as trimesh's ``exchange/``): :mod:`.ply`, :mod:`.obj`, :mod:`.off`,
:mod:`.stl`; :mod:`.common` (:class:`MeshData`, :func:`check_input_file`, shared parse helpers),
:mod:`.masks` (:func:`read_vertex_mask`). This module
dispatches :func:`read_mesh` and :func:`write_mesh` on the file extension.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from meshrepair.atomic import atomic_write, check_writable
from meshrepair.errors import MeshRepairError
from meshrepair.io.common import MeshData, PathLike, _Bad, _fail_read, _suffix, check_input_file
from meshrepair.io.masks import read_vertex_mask
from meshrepair.io.obj import _read_obj, _write_obj
from meshrepair.io.off import _read_off, _write_off
from meshrepair.io.ply import _ply_attr_columns, _read_ply, _write_ply
from meshrepair.io.stl import _read_stl, _write_stl
from meshrepair.mesh.array_contract import _as_face_array, _as_vertex_array, as_arrays

logger = logging.getLogger(__name__)

__all__ = [
    "SUPPORTED_FORMATS",
    "MeshData",
    "as_arrays",
    "check_input_file",
    "read_mesh",
    "read_vertex_mask",
    "write_mesh",
]

SUPPORTED_FORMATS = (".obj", ".off", ".ply", ".stl")
"""File extensions understood by :func:`read_mesh` and :func:`write_mesh`."""

_READERS = {".ply": _read_ply, ".obj": _read_obj, ".off": _read_off, ".stl": _read_stl}


def read_mesh(path: PathLike) -> MeshData:
    """Read a triangle mesh from a PLY, OBJ, OFF or STL file, unaltered.

    Vertex order and faces are kept exactly as stored (no merging, reordering or removal of
    unreferenced vertices). Polygons are fan-triangulated in place (warning); STL triangle soup
    gets exactly-equal positions merged (info). OBJ: ``v`` and ``f`` lines are used (``a``,
    ``a/b``, ``a//c``, ``a/b/c`` and negative relative indices); ``vt``, ``vn``, groups,
    materials, lines and points are ignored.

    Parameters
    ----------
    path : str or os.PathLike
        File with extension ``.ply``, ``.obj``, ``.off`` or ``.stl`` (case-insensitive).

    Returns
    -------
    MeshData
        ``V`` (nV, 3) float64, ``F`` (nF, 3) int64, PLY per-vertex ``vertex_attributes`` and
        ``path``. A PLY without faces gives ``F`` of shape (0, 3) (warning).

    Raises
    ------
    MeshRepairError
        If the file is missing, has an unsupported extension, or is not a valid mesh file
        (garbage, truncated, face indices out of range, ...); the message names the file.
    """
    p = Path(path)
    ext = _suffix(p)
    if ext not in _READERS:
        raise _fail_read(p, f"unsupported file extension {ext or '(none)'!r} (supported: "
                            f"{', '.join(SUPPORTED_FORMATS)})")
    check_input_file(p)
    try:
        mesh = _READERS[ext](p)
    except _Bad as exc:
        raise _fail_read(p, str(exc)) from None
    except OSError as exc:
        raise _fail_read(p, exc.strerror or str(exc)) from None
    except MemoryError:
        raise _fail_read(p, "out of memory (corrupt counts in the header?)") from None
    except (ValueError, IndexError, TypeError) as exc:  # anything the parsers did not foresee
        raise _fail_read(p, f"corrupt file ({type(exc).__name__}: {exc})") from None
    logger.debug("read %s: %d vertices, %d faces", p, mesh.n_vertices, mesh.n_faces)
    return mesh


def write_mesh(
    path: PathLike,
    V: np.ndarray,
    F: np.ndarray,
    *,
    vertex_attributes: Mapping[str, np.ndarray] | None = None,
    binary: bool = True,
    overwrite: bool = True,
) -> Path:
    """Write a triangle mesh; the format follows the extension.

    ``.ply``: binary little-endian (or ASCII if ``binary=False``), ``double x, y, z`` plus one
    property per vertex attribute (its dtype kept: float32/64, (u)int8/16/32; bool as ``uchar``,
    int64 as ``int`` if it fits), faces as ``uchar`` count + ``int`` indices.
    ``.obj`` / ``.off``: ASCII with 17 significant digits (exact float64 round trip).
    ``.stl``: binary (float32, warning if coordinates are rounded) or ASCII if ``binary=False``
    (17 digits). Vertex attributes are only stored in PLY (ignored with a warning otherwise);
    STL cannot store shared vertices or unreferenced vertices.

    Parameters
    ----------
    path : str or os.PathLike
    V : (nV, 3) array_like of float
        Must be finite.
    F : (nF, 3) array_like of int
        0-based indices into ``V``.
    vertex_attributes : mapping of str to (nV,) array_like, optional
        Extra per-vertex scalar properties (PLY only).
    binary : bool, optional
        Binary PLY/STL (default) or ASCII.
    overwrite : bool, optional
        If False and ``path`` exists, raise instead of replacing it.

    Returns
    -------
    pathlib.Path
        The written path.

    Raises
    ------
    MeshRepairError
        Unsupported extension, existing file with ``overwrite=False``, non-finite ``V``, bad
        shapes or indices, invalid attributes, or an OS error while writing.
    """
    p = Path(path)
    ext = _suffix(p)
    if ext not in _READERS:
        raise MeshRepairError(f"cannot write '{p}': unsupported file extension "
                              f"{ext or '(none)'!r} (supported: {', '.join(SUPPORTED_FORMATS)})")
    check_writable(p, overwrite=overwrite)
    Vf = _as_vertex_array(V, f"cannot write '{p}'")
    Fi = _as_face_array(F, f"cannot write '{p}'")
    if Fi.size == 0:
        Fi = Fi.reshape(0, 3)
    if Vf.ndim != 2 or Vf.shape[1] != 3:
        raise MeshRepairError(f"cannot write '{p}': V must have shape (nV, 3), got {Vf.shape}")
    if Fi.ndim != 2 or Fi.shape[1] != 3:
        raise MeshRepairError(f"cannot write '{p}': F must have shape (nF, 3), got {Fi.shape}")
    if len(Vf) == 0:
        raise MeshRepairError(f"cannot write '{p}': the mesh has no vertices (nothing to write)")
    bad = ~np.isfinite(Vf).all(axis=1)
    if bad.any():
        idx = np.flatnonzero(bad)
        raise MeshRepairError(
            f"refusing to write '{p}': {len(idx)} vertices have non-finite (NaN/inf) coordinates "
            f"(first: {idx[:5].tolist()})"
        )
    nV = len(Vf)
    if Fi.size and (Fi.min() < 0 or Fi.max() >= nV):
        raise MeshRepairError(
            f"cannot write '{p}': face indices out of range [0, {nV - 1}] "
            f"(got [{int(Fi.min())}, {int(Fi.max())}])"
        )
    if ext == ".ply":
        if nV and Fi.size and Fi.max() > np.iinfo(np.int32).max:
            raise MeshRepairError(f"cannot write '{p}': too many vertices for PLY int indices")
        attrs = _ply_attr_columns(vertex_attributes, nV)
    else:
        attrs = []
        if vertex_attributes:
            logger.warning("%s: vertex attributes %s are not stored in %s files (use PLY)", p,
                           sorted(vertex_attributes), ext)
    with atomic_write(p, "wb", overwrite=overwrite) as fh:
        if ext == ".ply":
            _write_ply(fh, Vf, Fi, attrs, binary)
        elif ext == ".stl":
            _write_stl(fh, Vf, Fi, binary, p)
        elif ext == ".obj":
            _write_obj(fh, Vf, Fi)
        else:  # .off
            _write_off(fh, Vf, Fi)
    logger.debug("wrote %s: %d vertices, %d faces", p, nV, len(Fi))
    return p

