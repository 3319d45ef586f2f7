"""PLY reading and writing.

PLY is read with :mod:`plyfile` (ASCII and binary, any byte order; a fast memory-mapped path for
triangle meshes, the generic path for polygons); extra per-vertex scalar properties (e.g. a mask,
colours, quality) are returned in :attr:`MeshData.vertex_attributes`. The header's element
counts must account for all the data: a header that overcounts (more records than the file can
hold) or undercounts (data after the last declared record) is refused.

Written as binary little-endian PLY (or ASCII), ``double x, y, z``, one property per vertex
attribute (its dtype kept), faces as ``uchar`` count + ``int`` indices, directly with numpy
(plyfile serialises list elements record by record).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.io.attributes import FileFormat
from meshrepair.io.common import MeshData, _Bad, _check_indices, _fan_triangulate, _undercount

logger = logging.getLogger("meshrepair.io")

_PLY_FACE_NAMES = ("vertex_indices", "vertex_index")
_PLY_TYPES = {
    np.dtype(np.int8): "char", np.dtype(np.uint8): "uchar",
    np.dtype(np.int16): "short", np.dtype(np.uint16): "ushort",
    np.dtype(np.int32): "int", np.dtype(np.uint32): "uint",
    np.dtype(np.float32): "float", np.dtype(np.float64): "double",
}


def _load_ply(path: Path) -> Any:
    """Parse a PLY file with plyfile (fast memory-mapped path for triangle meshes) and check
    that the header's element counts account for all the data (no silently ignored rest)."""
    import plyfile

    with open(path, "rb") as fh:
        magic = fh.read(4)
    if magic[:3] != b"ply":
        raise _Bad("not a PLY file (bad header: missing 'ply' magic line)")
    _check_ply_counts(path)
    known = {"face": dict.fromkeys(_PLY_FACE_NAMES, 3)}
    try:
        try:
            with open(path, "rb") as fh:
                ply = plyfile.PlyData.read(fh, mmap="c", known_list_len=known)
                end = None if ply.text else fh.tell()
        except plyfile.PlyElementParseError as exc:
            if exc.message != "unexpected list length":
                raise
            with open(path, "rb") as fh:  # polygons: slow generic path
                ply = plyfile.PlyData.read(fh, mmap=False)
                end = None if ply.text else fh.tell()
    except plyfile.PlyHeaderParseError as exc:
        raise _Bad(f"not a PLY file (bad header: {exc})") from None
    except plyfile.PlyElementParseError as exc:
        raise _Bad(f"truncated or corrupt PLY data ({exc})") from None
    except (ValueError, TypeError, IndexError, KeyError, EOFError, OSError) as exc:
        raise _Bad(f"corrupt PLY file ({type(exc).__name__}: {exc})") from None
    _check_ply_extent(path, ply, end)
    return ply


def _check_ply_counts(path: Path) -> None:
    """Refuse, before any allocation, a header whose element counts cannot fit in the file
    (each record takes at least 1 byte in binary, 2 in ASCII: a value and a line end)."""
    with open(path, "rb") as fh:
        head = fh.read(1 << 16)
    end = head.find(b"end_header")
    if end < 0:
        return  # plyfile reports the bad header
    counts, ascii_ = [], False
    for line in head[:end].decode("ascii", "replace").splitlines():
        t = line.split()
        if len(t) >= 2 and t[0] == "format":
            ascii_ = t[1] == "ascii"
        elif len(t) == 3 and t[0] == "element" and t[2].isdigit():
            counts.append((t[1], int(t[2])))
    need = sum(c for _, c in counts) * (2 if ascii_ else 1)
    size = path.stat().st_size - end
    if need > size:
        desc = ", ".join(f"{c:,} {n}" for n, c in counts)
        raise _Bad(f"the header declares {desc} records, which need at least {need:,} bytes, "
                   f"but the file has {size:,} bytes of data (corrupt header or truncated file)")


def _ply_counts(ply: Any) -> str:
    return ", ".join(f"{e.count} {e.name}" for e in ply.elements)


def _check_ply_extent(path: Path, ply: Any, end: int | None) -> None:
    """Refuse data after the last element the header declares (a header that undercounts)."""
    size = path.stat().st_size
    if end is not None:  # binary: the parser stopped at byte ``end``
        if size > end:
            with open(path, "rb") as fh:
                fh.seek(end)
                tail = fh.read(min(size - end, 1 << 16))
            if size - end > len(tail) or tail.strip(b" \t\r\n"):
                raise _undercount(f"the header declares {_ply_counts(ply)} records but "
                                  f"{size - end} more bytes follow them")
        return
    data = path.read_bytes()  # ASCII: one line per element record after 'end_header'
    h = data.find(b"end_header")
    start = data.find(b"\n", h) + 1 if h >= 0 else 0
    if start <= 0:
        return
    n_rec = sum(int(e.count) for e in ply.elements)
    nl = np.flatnonzero(np.frombuffer(data, np.uint8, offset=start) == 10)
    if n_rec == 0:
        rest = data[start:]
    elif len(nl) < n_rec:  # the last record has no newline
        rest = b""
    else:
        rest = data[start + int(nl[n_rec - 1]) + 1:]
    if rest.strip():
        extra = len([ln for ln in rest.splitlines() if ln.strip()])
        raise _undercount(f"the header declares {_ply_counts(ply)} records but {extra} more "
                          "data lines follow them")


def _ply_scalar_props(element: Any) -> list[Any]:
    import plyfile

    return [p for p in element.properties if not isinstance(p, plyfile.PlyListProperty)]


def _whole_indices(a: np.ndarray, name: str) -> np.ndarray:
    """Vertex indices as int64; a float list property is accepted only with whole values (a
    fractional index is a broken file, not one to truncate)."""
    if a.dtype.kind == "f":
        bad = ~np.isfinite(a) | (a != np.round(a))
        if bad.any():
            raise _Bad(f"face property {name!r} holds {int(bad.sum())} non-integer vertex "
                       f"indices (first: {a[bad][0]!r}); indices must be whole numbers")
    elif a.dtype.kind not in "iu":
        raise _Bad(f"face property {name!r} has type {a.dtype}, not integer vertex indices")
    return a.astype(np.int64)


def _read_ply(path: Path) -> MeshData:
    import plyfile

    ply = _load_ply(path)
    names = [e.name for e in ply.elements]
    if "vertex" not in names:
        raise _Bad(f"no 'vertex' element (elements: {names})")
    vert = ply["vertex"]
    props = [p.name for p in vert.properties]
    missing = [c for c in "xyz" if c not in props]
    if missing:
        raise _Bad(f"vertex element lacks properties {missing} (has {props})")
    data = vert.data
    V = np.empty((vert.count, 3), dtype=np.float64)
    for k, c in enumerate("xyz"):
        V[:, k] = data[c]
    attrs: dict[str, np.ndarray] = {}
    for p in _ply_scalar_props(vert):
        if p.name not in ("x", "y", "z"):
            col = data[p.name]
            attrs[p.name] = np.array(col, dtype=col.dtype.newbyteorder("="))
    skipped = [p.name for p in vert.properties
               if isinstance(p, plyfile.PlyListProperty)]
    if skipped:
        logger.warning("%s: per-vertex list properties %s are not kept (only scalar vertex "
                       "properties are)", path, skipped)
    others = [n for n in names if n not in ("vertex", "face")]
    if others:
        logger.warning("%s: PLY elements %s are not kept (only 'vertex' and 'face' are)", path,
                       others)
    xdt = np.dtype(data["x"].dtype)
    fmt = FileFormat(binary=not ply.text,
                     precision="float32" if xdt.kind == "f" and xdt.itemsize == 4
                     else "float64",
                     comments=[str(c) for c in ply.comments]
                     + [f"obj_info {c}" for c in getattr(ply, "obj_info", [])])

    face_attrs: dict[str, np.ndarray] = {}
    texcoords = face_tc = None
    if "face" not in names:
        if "tristrips" in names:
            raise _Bad("faces stored as 'tristrips' are not supported; convert to triangles")
        logger.warning("%s: no 'face' element: the file holds a point cloud (0 faces)", path)
        F = np.empty((0, 3), dtype=np.int64)
    else:
        face = ply["face"]
        lists = [p.name for p in face.properties if isinstance(p, plyfile.PlyListProperty)]
        key = next((n for n in _PLY_FACE_NAMES if n in lists), lists[0] if lists else None)
        if key is None:
            raise _Bad("the 'face' element has no list property of vertex indices")
        col = face.data[key]
        if col.dtype != object and col.ndim == 2:  # fixed-length (memory-mapped) triangles
            counts = np.full(len(col), col.shape[1], dtype=np.int64)
            flat = _whole_indices(np.asarray(col).ravel(), key)
        else:
            counts = np.fromiter((len(a) for a in col), dtype=np.int64, count=len(col))
            flat = (_whole_indices(np.concatenate([np.asarray(a) for a in col]), key)
                    if len(col) else np.empty(0, dtype=np.int64))
        F = _fan_triangulate(flat, counts, str(path))
        per_tri = np.repeat(np.arange(len(counts)), np.maximum(counts - 2, 0))
        for p in _ply_scalar_props(face):
            c = face.data[p.name]
            face_attrs[p.name] = np.array(c, dtype=c.dtype.newbyteorder("="))[per_tri]
        if "texcoord" in lists and key != "texcoord":
            texcoords, face_tc = _corner_texcoords(face.data["texcoord"], counts, path)
        dropped = [n for n in lists if n not in (key, "texcoord")]
        if dropped:
            logger.warning("%s: per-face list properties %s are not kept", path, dropped)
    del ply, data
    _check_indices(F, len(V))
    return MeshData(V=V, F=F, vertex_attributes=attrs, path=path, face_attributes=face_attrs,
                    texcoords=texcoords, face_texcoords=face_tc, file_format=fmt)


def _corner_texcoords(col: Any, counts: np.ndarray, path: Path
                      ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Per-corner texture coordinates from a face ``texcoord`` list (``u0 v0 u1 v1 ...``, the
    layout MeshLab writes), fan-triangulated like the faces: a (nT, 2) table, one row per
    polygon corner, and (nF, 3) indices into it."""
    lens = np.fromiter((len(a) for a in col), dtype=np.int64, count=len(col))
    if not np.array_equal(lens, 2 * counts):
        logger.warning("%s: the face 'texcoord' lists do not hold 2 values per corner; texture "
                       "coordinates are not kept", path)
        return None, None
    table = (np.concatenate([np.asarray(a, np.float64) for a in col]).reshape(-1, 2)
             if len(col) else np.empty((0, 2)))
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    ntri = np.maximum(counts - 2, 0)
    first = np.repeat(starts, ntri)
    j = np.arange(int(ntri.sum())) - np.repeat(np.cumsum(ntri) - ntri, ntri) + 1
    return table, np.stack([first, first + j, first + j + 1], axis=1).astype(np.int64)


def _ply_attr_columns(
    vertex_attributes: Mapping[str, Any] | None, nV: int, what: str = "vertex"
) -> list[tuple[str, np.ndarray, str]]:
    """Validate attributes for PLY output: (name, array, ply type) triples; ``what`` is
    ``"vertex"`` (nV = number of vertices) or ``"face"`` (nV = number of faces)."""
    reserved = ("x", "y", "z") if what == "vertex" else ("vertex_indices", "texcoord")
    out: list[tuple[str, np.ndarray, str]] = []
    for name, values in (vertex_attributes or {}).items():
        if not isinstance(name, str) or not name or not name.isascii() \
                or not name.isprintable() or any(ch.isspace() for ch in name) or name in reserved:
            raise MeshRepairError(
                f"invalid {what} attribute name {name!r}: use a non-empty ASCII name without "
                f"spaces (a PLY header is ASCII), other than {', '.join(reserved)}"
            )
        a = np.asarray(values)
        if a.ndim == 2 and a.shape[1] == 1:
            a = a[:, 0]
        if a.shape != (nV,):
            raise MeshRepairError(
                f"{what} attribute {name!r} has shape {a.shape}, expected ({nV},) "
                f"(one scalar per {what})"
            )
        if a.dtype == bool:
            a = a.astype(np.uint8)
        elif a.dtype == np.float16:
            a = a.astype(np.float32)
        elif a.dtype in (np.dtype(np.int64), np.dtype(np.uint64)):
            target = np.int32 if a.dtype == np.int64 else np.uint32
            info = np.iinfo(target)
            if a.size and (a.min() < info.min or a.max() > info.max):
                raise MeshRepairError(
                    f"{what} attribute {name!r} has values outside the 32-bit range of PLY "
                    "integers; convert it to float64"
                )
            a = a.astype(target)
        a = a.astype(a.dtype.newbyteorder("="), copy=False)
        if a.dtype not in _PLY_TYPES:
            raise MeshRepairError(
                f"{what} attribute {name!r} has dtype {a.dtype}, which PLY cannot store "
                "(use a float or integer array)"
            )
        out.append((name, a, _PLY_TYPES[a.dtype]))
    return out


def _write_ply(fh: Any, V: np.ndarray, F: np.ndarray, attrs: list[tuple[str, np.ndarray, str]],
               binary: bool, *, coord: Any = "f8",
               face_attrs: list[tuple[str, np.ndarray, str]] = (),
               corner_uv: np.ndarray | None = None, comments: list[str] = ()) -> None:
    """Write PLY: ``x, y, z`` in ``coord`` (float or double), then ``attrs``; faces as ``uchar``
    count + ``int`` indices, then ``face_attrs``, then (if given) a ``texcoord`` list of the
    (nF, 6) per-corner texture coordinates ``corner_uv``."""
    # Written directly (not via plyfile, which serialises list elements record by record);
    # the layout is the standard one and is read back by plyfile.
    fmt = "binary_little_endian" if binary else "ascii"
    ct = _PLY_TYPES[np.dtype(coord)]
    header = ["ply", f"format {fmt} 1.0"]
    header += [("obj_info " + c[9:]) if c.startswith("obj_info ") else f"comment {c}"
               for c in comments]
    header += [f"element vertex {len(V)}", f"property {ct} x", f"property {ct} y",
               f"property {ct} z"]
    header += [f"property {t} {n}" for n, _, t in attrs]
    header += [f"element face {len(F)}", "property list uchar int vertex_indices"]
    header += [f"property {t} {n}" for n, _, t in face_attrs]
    if corner_uv is not None:
        header.append("property list uchar float texcoord")
    header.append("end_header")
    fh.write(("\n".join(header) + "\n").encode("ascii"))
    # the records' field names are positional (the header carries the user's names, which may
    # be anything PLY allows, e.g. "n" or "i" for a face property)
    cs = np.dtype(coord).newbyteorder("<").str
    vdtype = [("x", cs), ("y", cs), ("z", cs)]
    vdtype += [(f"a{k}", a.dtype.newbyteorder("<").str) for k, (_, a, _) in enumerate(attrs)]
    vrec = np.empty(len(V), dtype=vdtype)
    vrec["x"], vrec["y"], vrec["z"] = V[:, 0], V[:, 1], V[:, 2]
    for k, (_, a, _) in enumerate(attrs):
        vrec[f"a{k}"] = a
    fdtype = [("count", "u1"), ("indices", "<i4", (3,))]
    fdtype += [(f"a{k}", a.dtype.newbyteorder("<").str) for k, (_, a, _) in enumerate(face_attrs)]
    if corner_uv is not None:
        fdtype += [("uv_count", "u1"), ("uv", "<f4", (6,))]
    frec = np.empty(len(F), dtype=fdtype)
    frec["count"] = 3
    frec["indices"] = F
    for k, (_, a, _) in enumerate(face_attrs):
        frec[f"a{k}"] = a
    if corner_uv is not None:
        frec["uv_count"] = 6
        frec["uv"] = corner_uv
    if binary:
        fh.write(vrec.tobytes())
        fh.write(frec.tobytes())
        return
    cf = "%.9g" if np.dtype(coord) == np.float32 else "%.17g"
    fmts = [cf] * 3 + [_ascii_fmt(a) for _, a, _ in attrs]
    if len(V):
        np.savetxt(fh, vrec, fmt=fmts, delimiter=" ")
    if len(F):
        cols = [np.full((len(F), 1), 3), F] + [a.reshape(-1, 1) for _, a, _ in face_attrs]
        ffmts = ["%d"] * 4 + [_ascii_fmt(a) for _, a, _ in face_attrs]
        if corner_uv is not None:
            cols += [np.full((len(F), 1), 6), corner_uv.astype(np.float32)]
            ffmts += ["%d"] + ["%.9g"] * 6
        table = np.concatenate([np.asarray(c, dtype=np.float64) for c in cols], axis=1)
        np.savetxt(fh, table, fmt=ffmts, delimiter=" ")


def _ascii_fmt(a: np.ndarray) -> str:
    return "%.9g" if a.dtype == np.float32 else "%.17g" if a.dtype.kind == "f" else "%d"
