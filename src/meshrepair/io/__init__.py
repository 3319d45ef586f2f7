"""Reading and writing triangle meshes (PLY, OBJ, OFF, STL) without altering them.

Readers keep the vertex order and the face list exactly as stored in the file: nothing is
merged, reordered, re-oriented or removed (unreferenced vertices stay). Two exceptions, both
logged:

* polygons with more than 3 vertices (OBJ, OFF, PLY) are fan-triangulated in place,
  ``[a, b, c, d] -> [a, b, c], [a, c, d]`` (warning with the count);
* STL stores an unconnected triangle soup, so exactly equal corner positions are merged into
  one vertex (``-0.0`` equals ``0.0``), vertices numbered in order of first appearance (info).

PLY is read with :mod:`plyfile` (ASCII and binary, any byte order); extra per-vertex scalar
properties (e.g. a mask, colours, quality) are returned in :attr:`MeshData.vertex_attributes`,
per-face ones in :attr:`MeshData.face_attributes`, with the file's storage
(:class:`FileFormat`: binary or ASCII, float32 or float64 coordinates, comments). OBJ, OFF and
STL use small exact numpy parsers (no trimesh loaders: they merge and reorder); OBJ texture
coordinates, normals, vertex colours and materials and OFF colours are kept too. A repaired
mesh gets the attributes of its input with :func:`carry_attributes` (:mod:`.carry`) and is
written like its input with ``write_mesh(path, V, F, like=mesh)``.

Writers produce binary little-endian PLY (``double`` or ``float x, y, z``, faces ``uchar``
count + ``int`` indices, one property per vertex attribute), ASCII PLY, OBJ and OFF (17
significant digits, so float64 values round-trip exactly) and binary or ASCII STL (binary STL
stores float32: a warning is logged when coordinates lose precision). Files are written to a
temporary file in the target directory and then renamed, so a failed write never leaves a
truncated mesh behind.

Every failure raises :class:`~meshrepair.errors.MeshRepairError` naming the file and the problem.

Modules (one per format, as trimesh's ``exchange/``): :mod:`.ply`, :mod:`.obj`, :mod:`.off`,
:mod:`.stl`; :mod:`.common` (:class:`MeshData`, :func:`check_input_file`, shared parse helpers),
:mod:`.masks` (:func:`read_vertex_mask`), :mod:`.attributes` (:class:`FileFormat`, kinds of
attributes, precision rule), :mod:`.carry` (:func:`carry_attributes`),
:mod:`.trimesh_visuals` (:func:`from_trimesh`, :func:`to_trimesh`). This module
dispatches :func:`read_mesh` and :func:`write_mesh` on the file extension.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from meshrepair.atomic import atomic_write, check_writable
from meshrepair.errors import MeshRepairError
from meshrepair.io.attributes import FileFormat, coordinate_dtype, uv_pair
from meshrepair.io.carry import carry_attributes
from meshrepair.io.common import MeshData, PathLike, _Bad, _fail_read, _suffix, check_input_file
from meshrepair.io.masks import read_vertex_mask
from meshrepair.io.obj import _read_obj, _write_obj
from meshrepair.io.off import _read_off, _write_off
from meshrepair.io.ply import _ply_attr_columns, _read_ply, _write_ply
from meshrepair.io.stl import _read_stl, _write_stl
from meshrepair.io.trimesh_visuals import from_trimesh, to_trimesh
from meshrepair.mesh.array_contract import _as_face_array, _as_vertex_array, as_arrays

logger = logging.getLogger(__name__)

__all__ = [
    "SUPPORTED_FORMATS",
    "FileFormat",
    "MeshData",
    "as_arrays",
    "carry_attributes",
    "check_input_file",
    "from_trimesh",
    "read_mesh",
    "read_vertex_mask",
    "to_trimesh",
    "write_like_input",
    "write_mesh",
]

SUPPORTED_FORMATS = (".obj", ".off", ".ply", ".stl")
"""File extensions understood by :func:`read_mesh` and :func:`write_mesh`."""

_READERS = {".ply": _read_ply, ".obj": _read_obj, ".off": _read_off, ".stl": _read_stl}


def read_mesh(path: PathLike) -> MeshData:
    """Read a triangle mesh from a PLY, OBJ, OFF or STL file, unaltered.

    Vertex order and faces are kept exactly as stored (no merging, reordering or removal of
    unreferenced vertices). Polygons are fan-triangulated in place (warning); STL triangle soup
    gets exactly-equal positions merged (info). OBJ: ``v`` and ``f`` lines (``a``, ``a/b``,
    ``a//c``, ``a/b/c`` and negative relative indices), ``vt`` per corner, ``vn`` (per vertex),
    vertex colours, ``mtllib`` and ``usemtl`` are read; groups, lines and points are not kept
    (warning).

    Parameters
    ----------
    path : str or os.PathLike
        File with extension ``.ply``, ``.obj``, ``.off`` or ``.stl`` (case-insensitive).

    Returns
    -------
    MeshData
        ``V`` (nV, 3) float64, ``F`` (nF, 3) int64, per-vertex ``vertex_attributes``, per-face
        ``face_attributes``, texture coordinates, materials, ``file_format`` and ``path``.
        A PLY without faces gives ``F`` of shape (0, 3) (warning).

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
    except (ValueError, IndexError, TypeError, OverflowError) as exc:  # what the parsers missed
        raise _fail_read(p, f"corrupt file ({type(exc).__name__}: {exc})") from None
    logger.debug("read %s: %d vertices, %d faces", p, mesh.n_vertices, mesh.n_faces)
    return mesh


def write_mesh(
    path: PathLike,
    V: np.ndarray,
    F: np.ndarray,
    *,
    vertex_attributes: Mapping[str, np.ndarray] | None = None,
    binary: bool | None = None,
    overwrite: bool = True,
    like: MeshData | None = None,
    precision: str | None = None,
) -> Path:
    """Write a triangle mesh; the format follows the extension.

    ``.ply``: binary little-endian (or ASCII if ``binary=False``), ``x, y, z`` as ``double``
    (or ``float``, see ``precision``) plus one property per vertex attribute (its dtype kept:
    float32/64, (u)int8/16/32; bool as ``uchar``, int64 as ``int`` if it fits), faces as
    ``uchar`` count + ``int`` indices, then the per-face properties and per-corner texture
    coordinates (``texcoord`` list) of ``like``.
    ``.obj``: ASCII with 17 significant digits (exact float64 round trip), with the vertex
    colours, normals, texture coordinates, ``mtllib`` and ``usemtl`` of ``like``.
    ``.off``: ASCII (17 digits), COFF when the vertex attributes hold ``red, green, blue``.
    ``.stl``: binary (float32, warning if coordinates are rounded) or ASCII if ``binary=False``
    (17 digits); STL stores no shared or unreferenced vertices and no attributes.
    Whatever the format cannot hold is named in one warning (logged) per kind.

    Parameters
    ----------
    path : str or os.PathLike
    V : (nV, 3) array_like of float
        Must be finite.
    F : (nF, 3) array_like of int
        0-based indices into ``V``.
    vertex_attributes : mapping of str to (nV,) array_like, optional
        Extra per-vertex scalar properties, added to (or replacing) those of ``like``.
    binary : bool, optional
        Binary PLY/STL or ASCII; default: as ``like`` was stored, else binary. OBJ and OFF are
        text only: ``binary=True`` is refused for them.
    overwrite : bool, optional
        If False and ``path`` exists, raise instead of replacing it.
    like : MeshData, optional
        A mesh whose attributes and storage are written with (V, F): its
        ``vertex_attributes``, ``face_attributes``, texture coordinates, materials and
        :class:`FileFormat` (binary/ASCII, precision, comments). Its arrays must match V and F
        in length: it is the mesh returned by :func:`carry_attributes` for a repair, or the
        mesh read for an unchanged topology.
    precision : {"float32", "float64"}, optional
        Coordinate type of a PLY file; default: as ``like`` was stored, else float64.
        float32 is only used when it moves no vertex by more than 1e-3 mean edge lengths
        (else float64, logged): a float32 input is written as float32.

    Returns
    -------
    pathlib.Path
        The written path.

    Raises
    ------
    MeshRepairError
        Unsupported extension, existing file with ``overwrite=False``, non-finite ``V``, bad
        shapes or indices, invalid attributes, ``like`` of other sizes, or an OS error while
        writing.
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
    if precision not in (None, "float32", "float64"):
        raise MeshRepairError(f"precision must be 'float32' or 'float64', got {precision!r}")
    if like is not None:
        _check_like(like, nV, len(Fi), p)
    if binary is not None and not isinstance(binary, (bool, np.bool_)):
        raise MeshRepairError(f"binary must be True, False or None, got {binary!r}")
    if binary and ext in (".obj", ".off"):
        raise MeshRepairError(f"cannot write '{p}' with binary=True: {ext[1:].upper()} is written "
                              "as text only (use a .ply or .stl path for a binary file, or "
                              "binary=None)")
    fmt = like.file_format if like is not None and like.file_format is not None else None
    if binary is None:
        binary = fmt.binary if fmt is not None else True
    vattrs = {**(like.vertex_attributes if like is not None else {}), **(vertex_attributes or {})}
    with atomic_write(p, "wb", overwrite=overwrite) as fh:
        if ext == ".ply":
            if nV and Fi.size and Fi.max() > np.iinfo(np.int32).max:
                raise MeshRepairError(f"cannot write '{p}': too many vertices for PLY int indices")
            prec = precision or (fmt.precision if fmt is not None else "float64")
            _write_ply(fh, Vf, Fi, _ply_attr_columns(vattrs, nV), bool(binary),
                       coord=coordinate_dtype(Vf, Fi, prec, str(p)),
                       face_attrs=_ply_attr_columns(
                           like.face_attributes if like is not None else None, len(Fi), "face"),
                       corner_uv=_ply_corner_uv(like, p),
                       comments=fmt.comments if fmt is not None else [])
            _warn_dropped(p, like, {}, materials=True)
        elif ext == ".stl":
            _warn_dropped(p, like, vattrs, materials=True, faces=True, corners=True)
            _write_stl(fh, Vf, Fi, bool(binary), p)
        elif ext == ".obj":
            kept = {n: a for n, a in vattrs.items() if n in _obj_vertex_keeps(vattrs)}
            _warn_dropped(p, like, {n: a for n, a in vattrs.items() if n not in kept},
                          faces=True)
            _write_obj(fh, Vf, Fi, vattrs=kept, like=like)
        else:  # .off
            kept = {n: a for n, a in vattrs.items() if n in ("red", "green", "blue", "alpha")}
            _warn_dropped(p, like, {n: a for n, a in vattrs.items() if n not in kept},
                          materials=True, faces=True, corners=True)
            _write_off(fh, Vf, Fi, kept)
    logger.debug("wrote %s: %d vertices, %d faces", p, nV, len(Fi))
    return p


def write_like_input(out: PathLike, source: object, result: object, *, extra: dict | None = None,
                     force: bool = True, template: MeshData | None = None,
                     template_map: np.ndarray | None = None) -> None:
    """Write a task's result with everything of its input it does not change.

    The input's attributes are carried over (:func:`meshrepair.io.carry_attributes`: colours,
    texture coordinates, materials, per-face properties; interpolated on new vertices; normals
    recomputed) and the file is stored like the input (binary or ASCII, float32 or float64,
    comments); ``extra`` per-vertex attributes (the command's own masks) are added for a PLY
    output only. What the output format cannot hold is named in one logged warning.
    """
    like = carry_attributes(source, result, template=template, template_map=template_map)
    extra = extra if Path(out).suffix.lower() == ".ply" else None
    write_mesh(out, like.V, like.F, vertex_attributes=extra or None, like=like,
               overwrite=force)


def _obj_vertex_keeps(vattrs: Mapping[str, np.ndarray]) -> set[str]:
    """Per-vertex attributes an OBJ file holds: colours, normals, one texture pair."""
    keep = {"red", "green", "blue"} if all(c in vattrs for c in ("red", "green", "blue")) \
        else set()
    keep |= {"nx", "ny", "nz"} if all(c in vattrs for c in ("nx", "ny", "nz")) else set()
    pair = uv_pair(vattrs)
    if pair is not None:
        keep |= set(pair)
    return keep


def _check_like(like: MeshData, nV: int, nF: int, p: Path) -> None:
    bad = []
    for n, a in like.vertex_attributes.items():
        if len(a) != nV:
            bad.append(f"vertex attribute {n!r} has {len(a)} values for {nV} vertices")
    for n, a in like.face_attributes.items():
        if len(a) != nF:
            bad.append(f"face attribute {n!r} has {len(a)} values for {nF} faces")
    for n in ("face_texcoords", "face_materials"):
        a = getattr(like, n)
        if a is not None and len(a) != nF:
            bad.append(f"{n} has {len(a)} rows for {nF} faces")
    if bad:
        raise MeshRepairError(
            f"cannot write '{p}' like the given mesh: {bad[0]}; after a repair, pass the mesh "
            "returned by carry_attributes(source, result) as like=")


def _ply_corner_uv(like: MeshData | None, p: Path) -> np.ndarray | None:
    """(nF, 6) per-corner texture coordinates for PLY's face ``texcoord`` list, or None."""
    if like is None or like.texcoords is None or like.face_texcoords is None:
        return None
    tc = like.face_texcoords
    if (tc < 0).any():
        logger.warning("%s: %d face corners have no texture coordinate; PLY's per-face "
                       "'texcoord' list needs one per corner: texture coordinates not written",
                       p, int((tc < 0).sum()))
        return None
    return like.texcoords[tc].reshape(len(tc), 6)


def _warn_dropped(p: Path, like: MeshData | None, vattrs: Mapping, *, materials: bool = False,
                  faces: bool = False, corners: bool = False) -> None:
    """One warning naming what the format of ``p`` cannot store."""
    lost = []
    if vattrs:
        lost.append(f"vertex attributes {sorted(vattrs)}")
    if like is not None:
        if faces and like.face_attributes:
            lost.append(f"face attributes {sorted(like.face_attributes)}")
        if corners and like.face_texcoords is not None:
            lost.append("texture coordinates")
        if materials and like.face_materials is not None and like.materials:
            lost.append(f"materials {like.materials}")
    if lost:
        logger.warning("%s: %s are not stored in %s files (use %s)", p, "; ".join(lost),
                       p.suffix.lower(), "PLY" if p.suffix.lower() != ".ply" else "OBJ")
