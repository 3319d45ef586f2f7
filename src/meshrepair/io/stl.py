"""STL reading and writing (binary and ASCII) with small exact numpy parsers.

STL stores an unconnected triangle soup, so exactly equal corner positions are merged into one
vertex (``-0.0`` equals ``0.0``), vertices numbered in order of first appearance (logged at info
level). Binary files are told from ASCII ones by the triangle count in the header and the file
size; a binary header that undercounts, a truncated file and an ASCII file cut short (even
between two facets) are refused. Binary STL stores float32: a warning is logged when
coordinates lose precision, and coordinates beyond float32 are refused; ASCII STL is written
with 17 significant digits.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path
from typing import Any

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.io.attributes import FileFormat
from meshrepair.io.common import MeshData, _Bad, _undercount

logger = logging.getLogger("meshrepair.io")

_STL_DTYPE = np.dtype([("normal", "<f4", (3,)), ("v", "<f4", (3, 3)), ("attr", "<u2")])
_STL_VERTEX = re.compile(rb"\bvertex\s+(\S+)\s+(\S+)\s+(\S+)", flags=re.IGNORECASE)
_STL_KEYWORDS = re.compile(
    rb"^[ \t]*(solid|endsolid)\b[^\n]*|\b(facet|outer|loop|vertex|endloop|endfacet)\b",
    flags=re.IGNORECASE | re.MULTILINE)
_STL_CODES = {b"solid": 0, b"endsolid": 1, b"facet": 2, b"outer": 3, b"loop": 4, b"vertex": 5,
              b"endloop": 6, b"endfacet": 7}
_STL_FACET = np.array([2, 3, 4, 5, 5, 5, 6, 7], dtype=np.int8)


def _check_ascii_stl_structure(data: bytes) -> None:
    """Check ``solid (facet outer loop vertex vertex vertex endloop endfacet)* endsolid``, one
    or more solids: a file cut short (even between two facets) or with a broken facet is refused
    instead of being read as fewer triangles."""
    codes = np.array([_STL_CODES[(a or b).lower()] for a, b in _STL_KEYWORDS.findall(data)],
                     dtype=np.int8)
    if len(codes) == 0 or codes[0] != 0:
        raise _Bad("not an STL file (ASCII 'solid' header but no facets)")
    starts = np.flatnonzero(codes == 0)
    ends = np.flatnonzero(codes == 1)
    if len(ends) < len(starts) or (len(ends) and ends[-1] != len(codes) - 1):
        n_ok = int(np.sum(codes == 7))
        raise _Bad(f"truncated or malformed ASCII STL: no 'endsolid' after the last facet "
                   f"(file cut short after {n_ok} facets?); refusing to read part of the mesh")
    for a, b in zip(starts, ends, strict=False):
        body = codes[a + 1:b]
        bad = len(body) % 8 != 0 or len(starts) != len(ends) or b < a
        if not bad and len(body):
            bad = not np.array_equal(body.reshape(-1, 8), np.broadcast_to(_STL_FACET,
                                                                          (len(body) // 8, 8)))
        if bad:
            good = 0
            while good + 8 <= len(body) and np.array_equal(body[good:good + 8], _STL_FACET):
                good += 8
            raise _Bad(f"truncated or malformed ASCII STL: facet {good // 8} of a solid is not "
                       "'facet normal ..., outer loop, 3 x vertex, endloop, endfacet'")


def _merge_soup(corners: np.ndarray, path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Merge exactly equal corner positions; vertices numbered by first appearance."""
    corners = np.ascontiguousarray(corners + 0.0)  # -0.0 -> 0.0
    if len(corners) == 0:
        return np.empty((0, 3)), np.empty((0, 3), dtype=np.int64)
    rows = corners.view(np.dtype((np.void, 24))).ravel()
    _, first, inv = np.unique(rows, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    V = corners[first[order]]
    F = rank[inv.ravel()].reshape(-1, 3).astype(np.int64)
    logger.info("%s: STL triangle soup: merged %d corners into %d vertices at exactly equal "
                "positions", path, len(corners), len(V))
    return V, F


def _read_stl(path: Path) -> MeshData:
    data = path.read_bytes()
    size = len(data)
    is_solid = data[:512].lstrip()[:5].lower() == b"solid"
    if size >= 84:
        n = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])
        expected = 84 + 50 * n
        if size == expected or (not is_solid and size > expected):
            if size - expected >= _STL_DTYPE.itemsize:
                raise _undercount(f"binary STL header declares {n} triangles ({expected} "
                                  f"bytes) but the file has {size} bytes: "
                                  f"{(size - expected) // 50} more triangle records follow")
            if size > expected:
                logger.warning("%s: %d trailing bytes after the binary STL data ignored", path,
                               size - expected)
            rec = np.frombuffer(data, dtype=_STL_DTYPE, count=n, offset=84)
            if n and rec["attr"].any():
                logger.warning("%s: the per-facet attribute bytes of the binary STL (facet "
                               "colours in some exporters) are not kept", path)
            corners = rec["v"].reshape(-1, 3).astype(np.float64)
            V, F = _merge_soup(corners, path)
            return MeshData(V=V, F=F, path=path, file_format=FileFormat(binary=True,
                                                                       precision="float32"))
        if not is_solid or b"\x00" in data[84:]:  # binary (text STL has no NUL bytes)
            what = "truncated" if size < expected else "inconsistent"
            raise _Bad(f"{what} binary STL: header declares {n} triangles ({expected} bytes) "
                       f"but the file has {size} bytes")
    if not is_solid:
        raise _Bad("not an STL file (too short for binary STL and no ASCII 'solid' header)")
    _check_ascii_stl_structure(data)
    found = _STL_VERTEX.findall(data)
    if not found:
        return MeshData(V=np.empty((0, 3)), F=np.empty((0, 3), dtype=np.int64), path=path)
    try:
        corners = np.array(found, dtype=np.float64).reshape(-1, 3)
    except ValueError:
        raise _Bad("malformed ASCII STL vertex coordinates") from None
    V, F = _merge_soup(corners, path)
    return MeshData(V=V, F=F, path=path, file_format=FileFormat(binary=False))


def _write_stl(fh: Any, V: np.ndarray, F: np.ndarray, binary: bool, path: Path) -> None:
    if binary and len(V) and np.abs(V).max() > np.finfo(np.float32).max:
        raise MeshRepairError(
            f"cannot write '{path}': coordinates up to {np.abs(V).max():.3g} do not fit the "
            "float32 of binary STL; write PLY, OBJ or ASCII STL (binary=False)")
    # face normals from edges scaled per face: no overflow for huge coordinates
    e1, e2 = V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]
    with np.errstate(over="ignore", invalid="ignore"):
        s = np.maximum(np.abs(e1).max(axis=1), np.abs(e2).max(axis=1))[:, None]
        s = np.where(np.isfinite(s) & (s > 0), s, 1.0)
        c = np.cross(e1 / s, e2 / s)
    nrm = np.linalg.norm(c, axis=1, keepdims=True)
    N = np.divide(c, nrm, out=np.zeros_like(c), where=(nrm > 0) & np.isfinite(nrm))
    if binary:
        V32 = V.astype(np.float32)
        if not np.array_equal(V32.astype(np.float64), V):
            logger.warning("%s: binary STL stores float32: vertex coordinates were rounded "
                           "(write PLY, OBJ or ASCII STL to keep float64)", path)
        rec = np.zeros(len(F), dtype=_STL_DTYPE)
        rec["normal"] = N
        rec["v"] = V32[F]
        head = b"binary STL written by meshrepair"
        fh.write(head.ljust(80, b" "))
        fh.write(np.uint32(len(F)).astype("<u4").tobytes())
        fh.write(rec.tobytes())
        return
    g = "%.17g %.17g %.17g"
    fmt = (f"  facet normal {g}\n    outer loop\n      vertex {g}\n      vertex {g}\n"
           f"      vertex {g}\n    endloop\n  endfacet")
    fh.write(b"solid meshrepair\n")
    if len(F):
        np.savetxt(fh, np.concatenate([N, V[F].reshape(-1, 9)], axis=1), fmt=fmt)
    fh.write(b"endsolid meshrepair\n")
