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
"""

from __future__ import annotations

import logging
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .atomic import atomic_write, check_writable
from .errors import MeshRepairError
from .validate import _as_face_array, _as_vertex_array

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

PathLike = str | os.PathLike


@dataclass
class MeshData:
    """A triangle mesh read from a file.

    Attributes
    ----------
    V : (nV, 3) float64
        Vertex positions, in file order.
    F : (nF, 3) int64
        Triangles (0-based vertex indices), in file order (polygons fan-triangulated in place).
    vertex_attributes : dict of str to (nV,) ndarray
        Extra per-vertex scalar properties found in a PLY file (dtype as stored), e.g. a mask.
    path : pathlib.Path or None
        The file the mesh was read from.
    """

    V: np.ndarray
    F: np.ndarray
    vertex_attributes: dict[str, np.ndarray] = field(default_factory=dict)
    path: Path | None = None

    @property
    def n_vertices(self) -> int:
        """Number of vertices."""
        return int(self.V.shape[0])

    @property
    def n_faces(self) -> int:
        """Number of faces."""
        return int(self.F.shape[0])


# ------------------------------------------------------------------------------------------------
# helpers
# ------------------------------------------------------------------------------------------------


class _Bad(Exception):
    """Internal: a parse problem, turned into MeshRepairError with the file name."""


def _fail_read(path: Path, why: str) -> MeshRepairError:
    return MeshRepairError(f"cannot read '{path}': {why}")


def check_input_file(path: PathLike, what: str = "") -> Path:
    """Check a file before opening it: every reader of the project calls this first.

    Refuses a missing file, an impossible path (too long, a file used as a folder, ...), a
    folder, and a FIFO, device or socket (opening a FIFO would block forever).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    MeshRepairError
        ``cannot read '<path>': <why>``.
    """
    import stat

    path = Path(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise _fail_read(path, f"{what}file not found") from None
    except OSError as exc:  # name too long, not a directory, permission denied, loop, ...
        raise _fail_read(path, exc.strerror or str(exc)) from None
    if stat.S_ISDIR(st.st_mode):
        raise _fail_read(path, "is a directory, not a file")
    if not stat.S_ISREG(st.st_mode):
        raise _fail_read(path, "not a regular file (a FIFO, device or socket); give a file")
    return path


def _suffix(path: Path) -> str:
    return path.suffix.lower()


def _fan_triangulate(flat: np.ndarray, counts: np.ndarray, what: str) -> np.ndarray:
    """Triangulate polygons given as a flat index list and per-polygon vertex counts.

    Parameters
    ----------
    flat : (sum(counts),) int64
    counts : (nP,) int64, all >= 3
    what : str
        Used in the warning (file name).

    Returns
    -------
    (sum(counts - 2), 3) int64
        Polygon ``[a, b, c, d, ...]`` becomes ``[a, b, c], [a, c, d], ...``, in polygon order.
    """
    counts = np.asarray(counts, dtype=np.int64)
    if len(counts) == 0:
        return np.empty((0, 3), dtype=np.int64)
    if (counts < 3).any():
        k = int(np.flatnonzero(counts < 3)[0])
        raise _Bad(f"face {k} has {int(counts[k])} vertices (a face needs at least 3)")
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    if (counts == 3).all():
        return flat.reshape(-1, 3).astype(np.int64, copy=False)
    ntri = counts - 2
    first = np.repeat(starts, ntri)
    j = np.arange(int(ntri.sum())) - np.repeat(np.cumsum(ntri) - ntri, ntri) + 1
    F = np.stack([flat[first], flat[first + j], flat[first + j + 1]], axis=1)
    n_poly = int((counts > 3).sum())
    logger.warning(
        "%s: fan-triangulated %d polygon(s) with more than 3 vertices into %d triangles "
        "(%d faces -> %d triangles)", what, n_poly, int(ntri[counts > 3].sum()), len(counts),
        len(F))
    return F.astype(np.int64, copy=False)


def _check_indices(F: np.ndarray, nV: int) -> None:
    if F.size and (F.min() < 0 or F.max() >= nV):
        bad = int(np.flatnonzero(((F < 0) | (F >= nV)).any(axis=1))[0])
        raise _Bad(
            f"face {bad} references vertex {F[bad].tolist()} but the file has {nV} vertices "
            "(corrupt face list)"
        )


def _read_text(path: Path) -> str:
    data = path.read_bytes()
    if b"\x00" in data[:4096]:
        raise _Bad(f"binary data found, not a text {_suffix(path)[1:].upper()} file")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def _parse_floats(rows: list[list[str]], what: str, line_of: Any) -> np.ndarray:
    if not rows:
        return np.empty((0, 3), dtype=np.float64)
    try:
        return np.array(rows, dtype=np.float64).reshape(len(rows), -1)
    except ValueError:
        for k, r in enumerate(rows):
            try:
                [float(t) for t in r]
            except ValueError:
                raise _Bad(f"malformed {what} at line {line_of(k)}: {' '.join(r)!r}") from None
        raise


# ------------------------------------------------------------------------------------------------
# PLY
# ------------------------------------------------------------------------------------------------

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
                raise _Bad(f"the header declares {_ply_counts(ply)} records but {size - end} "
                           "more bytes follow them (the header undercounts, or the file is "
                           "corrupt); refusing to drop data silently")
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
        raise _Bad(f"the header declares {_ply_counts(ply)} records but {extra} more data "
                   "lines follow them (the header undercounts, or the file is corrupt); "
                   "refusing to drop data silently")


def _ply_scalar_props(element: Any) -> list[Any]:
    import plyfile

    return [p for p in element.properties if not isinstance(p, plyfile.PlyListProperty)]


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
        logger.info("%s: ignoring per-vertex list properties %s", path, skipped)

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
            flat = np.asarray(col, dtype=np.int64).ravel()
        else:
            counts = np.fromiter((len(a) for a in col), dtype=np.int64, count=len(col))
            flat = (np.concatenate([np.asarray(a, dtype=np.int64) for a in col])
                    if len(col) else np.empty(0, dtype=np.int64))
        F = _fan_triangulate(flat, counts, str(path))
    del ply, data
    _check_indices(F, len(V))
    return MeshData(V=V, F=F, vertex_attributes=attrs, path=path)


def _ply_attr_columns(
    vertex_attributes: Mapping[str, Any] | None, nV: int
) -> list[tuple[str, np.ndarray, str]]:
    """Validate attributes for PLY output: (name, array, ply type) triples."""
    out: list[tuple[str, np.ndarray, str]] = []
    for name, values in (vertex_attributes or {}).items():
        if not isinstance(name, str) or not name or any(ch.isspace() for ch in name) \
                or name in ("x", "y", "z"):
            raise MeshRepairError(
                f"invalid vertex attribute name {name!r}: use a non-empty name without spaces, "
                "other than x, y, z"
            )
        a = np.asarray(values)
        if a.ndim == 2 and a.shape[1] == 1:
            a = a[:, 0]
        if a.shape != (nV,):
            raise MeshRepairError(
                f"vertex attribute {name!r} has shape {a.shape}, expected ({nV},) "
                "(one scalar per vertex)"
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
                    f"vertex attribute {name!r} has values outside the 32-bit range of PLY "
                    "integers; convert it to float64"
                )
            a = a.astype(target)
        a = a.astype(a.dtype.newbyteorder("="), copy=False)
        if a.dtype not in _PLY_TYPES:
            raise MeshRepairError(
                f"vertex attribute {name!r} has dtype {a.dtype}, which PLY cannot store "
                "(use a float or integer array)"
            )
        out.append((name, a, _PLY_TYPES[a.dtype]))
    return out


def _write_ply(fh: Any, V: np.ndarray, F: np.ndarray, attrs: list[tuple[str, np.ndarray, str]],
               binary: bool) -> None:
    # Written directly (not via plyfile, which serialises list elements record by record);
    # the layout is the standard one and is read back by plyfile.
    fmt = "binary_little_endian" if binary else "ascii"
    header = ["ply", f"format {fmt} 1.0", f"element vertex {len(V)}",
              "property double x", "property double y", "property double z"]
    header += [f"property {t} {n}" for n, _, t in attrs]
    header += [f"element face {len(F)}", "property list uchar int vertex_indices", "end_header"]
    fh.write(("\n".join(header) + "\n").encode("ascii"))
    vdtype = [("x", "<f8"), ("y", "<f8"), ("z", "<f8")]
    vdtype += [(n, a.dtype.newbyteorder("<").str) for n, a, _ in attrs]
    vrec = np.empty(len(V), dtype=vdtype)
    vrec["x"], vrec["y"], vrec["z"] = V[:, 0], V[:, 1], V[:, 2]
    for n, a, _ in attrs:
        vrec[n] = a
    frec = np.empty(len(F), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    frec["n"] = 3
    frec["i"] = F
    if binary:
        fh.write(vrec.tobytes())
        fh.write(frec.tobytes())
        return
    fmts = ["%.17g"] * 3 + ["%.9g" if a.dtype == np.float32 else "%.17g"
                            if a.dtype.kind == "f" else "%d" for _, a, _ in attrs]
    if len(V):
        np.savetxt(fh, vrec, fmt=fmts, delimiter=" ")
    if len(F):
        np.savetxt(fh, np.c_[np.full(len(F), 3), F], fmt="%d", delimiter=" ")


# ------------------------------------------------------------------------------------------------
# OBJ
# ------------------------------------------------------------------------------------------------


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


# ------------------------------------------------------------------------------------------------
# OFF
# ------------------------------------------------------------------------------------------------


def _read_off(path: Path) -> MeshData:
    text = _read_text(path)
    raw = text.splitlines()
    lines: list[str] = []
    line_no: list[int] = []
    for i, ln in enumerate(raw):
        s = ln.split("#", 1)[0].strip()
        if s:
            lines.append(s)
            line_no.append(i + 1)
    if not lines:
        raise _Bad("empty file, not an OFF file (bad header)")
    head = lines[0].split()
    kw = head[0]
    if not kw.endswith("OFF"):
        raise _Bad(f"not an OFF file (bad header: {lines[0][:40]!r}, expected 'OFF')")
    prefix = kw[:-3]
    if "4" in prefix or "n" in prefix or prefix.replace("ST", "").strip("CN"):
        raise _Bad(f"unsupported OFF variant {kw!r} (only 3-D OFF, COFF, NOFF, STOFF ...)")
    rest = head[1:]
    pos = 1
    if rest and rest[0].upper() == "BINARY":
        raise _Bad("binary OFF is not supported; convert it to ASCII OFF or PLY")
    if not rest:
        if len(lines) < 2:
            raise _Bad("truncated: missing the 'nV nF nE' counts line")
        rest = lines[1].split()
        pos = 2
    try:
        nv, nf = int(rest[0]), int(rest[1])
    except (ValueError, IndexError):
        raise _Bad(f"bad counts line {' '.join(rest)!r} (expected 'nV nF nE')") from None
    if nv < 0 or nf < 0:
        raise _Bad(f"negative counts in header ({nv} vertices, {nf} faces)")
    if len(lines) - pos < nv + nf:
        raise _Bad(
            f"truncated: header declares {nv} vertices and {nf} faces but only "
            f"{len(lines) - pos} data lines follow"
        )
    vtok = [ln.split() for ln in lines[pos:pos + nv]]
    short = [k for k, t in enumerate(vtok) if len(t) < 3]
    if short:
        k = short[0]
        raise _Bad(f"malformed vertex at line {line_no[pos + k]} (expected 'x y z')")
    V = _parse_floats([t[:3] for t in vtok], "vertex", lambda k: line_no[pos + k])
    fpos = pos + nv
    ftok = [ln.split() for ln in lines[fpos:fpos + nf]]
    try:
        counts = np.array([int(t[0]) for t in ftok], dtype=np.int64)
    except ValueError:
        raise _Bad("malformed face line (expected 'k i1 ... ik')") from None
    ok = np.fromiter((len(t) for t in ftok), dtype=np.int64, count=nf) >= counts + 1
    if not ok.all():
        k = int(np.flatnonzero(~ok)[0])
        raise _Bad(f"face at line {line_no[fpos + k]} lists fewer indices than its count")
    try:
        if nf and (counts == 3).all():
            flat = np.array([t[1:4] for t in ftok], dtype=np.int64).ravel()
        else:
            flat = np.array([s for t, c in zip(ftok, counts, strict=True) for s in t[1:c + 1]],
                            dtype=np.int64)
    except ValueError:
        raise _Bad("malformed face index (expected integers)") from None
    F = _fan_triangulate(flat, counts, str(path))
    _check_indices(F, len(V))
    extra = len(lines) - (fpos + nf)
    if extra:
        raise _Bad(f"the header declares {nv} vertices and {nf} faces but {extra} more data "
                   f"lines follow them (from line {line_no[fpos + nf]}: the header undercounts, "
                   "or the file is corrupt); refusing to drop data silently")
    return MeshData(V=V, F=F, path=path)


# ------------------------------------------------------------------------------------------------
# STL
# ------------------------------------------------------------------------------------------------

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
                raise _Bad(f"binary STL header declares {n} triangles ({expected} bytes) but "
                           f"the file has {size} bytes: {(size - expected) // 50} more "
                           "triangle records follow (the header undercounts, or the file is "
                           "corrupt); refusing to drop data silently")
            if size > expected:
                logger.warning("%s: %d trailing bytes after the binary STL data ignored", path,
                               size - expected)
            rec = np.frombuffer(data, dtype=_STL_DTYPE, count=n, offset=84)
            corners = rec["v"].reshape(-1, 3).astype(np.float64)
            V, F = _merge_soup(corners, path)
            return MeshData(V=V, F=F, path=path)
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
    return MeshData(V=V, F=F, path=path)


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


# ------------------------------------------------------------------------------------------------
# public API
# ------------------------------------------------------------------------------------------------

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
            fh.write(b"# written by meshrepair\n")
            if nV:
                np.savetxt(fh, Vf, fmt="v %.17g %.17g %.17g")
            if len(Fi):
                np.savetxt(fh, Fi + 1, fmt="f %d %d %d")
        else:  # .off
            fh.write(f"OFF\n{nV} {len(Fi)} 0\n".encode("ascii"))
            if nV:
                np.savetxt(fh, Vf, fmt="%.17g %.17g %.17g")
            if len(Fi):
                np.savetxt(fh, Fi, fmt="3 %d %d %d")
    logger.debug("wrote %s: %d vertices, %d faces", p, nV, len(Fi))
    return p


def as_arrays(mesh_or_V: Any, F: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """Float64/int64 copies of a mesh given as arrays, a trimesh.Trimesh or a MeshData.

    Only dtypes are converted here; use :func:`meshrepair.validate.check_mesh` for shapes and
    topology.

    Parameters
    ----------
    mesh_or_V : (nV, 3) array_like, trimesh.Trimesh or MeshData
    F : (nF, 3) array_like of int, optional
        Required with an array ``V``; must be omitted with a mesh object.

    Returns
    -------
    V : (nV, 3) float64
        A new array (never a view of the caller's data).
    F : (nF, 3) int64
        A new array; integral floats are converted.

    Raises
    ------
    MeshRepairError
        For any other input, missing/extra ``F``, non-numeric arrays or non-integer faces.
    """
    if isinstance(mesh_or_V, MeshData):
        if F is not None:
            raise MeshRepairError("pass either a MeshData or (V, F) arrays, not both")
        V_in, F_in = mesh_or_V.V, mesh_or_V.F
    elif _is_trimesh(mesh_or_V):
        if F is not None:
            raise MeshRepairError("pass either a trimesh.Trimesh or (V, F) arrays, not both")
        V_in, F_in = mesh_or_V.vertices, mesh_or_V.faces
    elif isinstance(mesh_or_V, (np.ndarray, list, tuple)):
        if F is None:
            raise MeshRepairError(
                "missing face array F: pass (V, F) arrays, a trimesh.Trimesh or a MeshData"
            )
        V_in, F_in = mesh_or_V, F
    else:
        raise MeshRepairError(
            f"expected (V, F) arrays, a trimesh.Trimesh or a MeshData, got "
            f"{type(mesh_or_V).__name__}"
        )
    V_out = _as_vertex_array(V_in, "mesh")
    F_out = _as_face_array(F_in, "mesh")
    # never hand back (a view of) the caller's memory
    if V_out is V_in or np.may_share_memory(V_out, V_in):
        V_out = V_out.copy()
    if F_out is F_in or np.may_share_memory(F_out, F_in):
        F_out = F_out.copy()
    return np.ascontiguousarray(V_out), np.ascontiguousarray(F_out)


def _is_trimesh(obj: object) -> bool:
    if not type(obj).__module__.startswith("trimesh"):
        return False
    import trimesh

    return isinstance(obj, trimesh.Trimesh)


# ------------------------------------------------------------------------------------------------
# vertex masks
# ------------------------------------------------------------------------------------------------

# vertex properties that are never taken as a mask when no name is given
_NOT_A_MASK = {"nx", "ny", "nz", "red", "green", "blue", "alpha", "r", "g", "b", "a",
               "s", "t", "u", "v", "texture_u", "texture_v", "intensity"}


def _mask_from_values(vals: np.ndarray, n_vertices: int, source: str) -> np.ndarray:
    """Bool mask from a per-vertex 0/1 array or from a list of vertex indices."""
    vals = np.asarray(vals)
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
    except ValueError:
        bad = next(t for t in tokens if not t.lstrip("+-").isdigit())
        raise _fail_read(p, f"expected integer vertex indices, found {bad!r}") from None
    return _mask_from_values(vals, n_vertices, src)
