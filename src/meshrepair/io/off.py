"""OFF reading and writing with a small exact numpy parser.

ASCII 3-D OFF and its COFF / NOFF / STOFF ... variants; ``#`` comments allowed; the counts line
may share the ``OFF`` line. COFF vertex colours are kept as ``red, green, blue, alpha``
(uchar when the file gives integers, else float) and written back as COFF; NOFF normals and
STOFF texture coordinates are not kept (warning), nor are per-face colours. Binary OFF and
4-D / n-D OFF are refused, and so is data after the declared vertices and faces. Written as
ASCII with 17 significant digits (exact float64 round trip).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

from meshrepair.io.attributes import FileFormat
from meshrepair.io.common import (
    MeshData,
    _Bad,
    _check_indices,
    _fan_triangulate,
    _parse_floats,
    _read_text,
    _undercount,
)

logger = logging.getLogger("meshrepair.io")


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
    vattrs = _off_colours(vtok, prefix, path) if "C" in prefix and nv else {}
    if "N" in prefix or "ST" in prefix:
        logger.warning("%s: %s normals / texture coordinates are not kept (only COFF colours "
                       "are)", path, kw)
    fpos = pos + nv
    ftok = [ln.split() for ln in lines[fpos:fpos + nf]]
    try:
        counts = np.array([int(t[0]) for t in ftok], dtype=np.int64)
    except (ValueError, OverflowError):
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
    except (ValueError, OverflowError):
        raise _Bad("malformed face index (expected integers below 2^63)") from None
    F = _fan_triangulate(flat, counts, str(path))
    _check_indices(F, len(V))
    extra = len(lines) - (fpos + nf)
    if extra:
        raise _undercount(f"the header declares {nv} vertices and {nf} faces but {extra} more "
                          "data lines follow them", f"from line {line_no[fpos + nf]}: ")
    if any(len(t) > c + 1 for t, c in zip(ftok, counts, strict=True)):
        logger.warning("%s: per-face colours of the OFF file are not kept", path)
    return MeshData(V=V, F=F, vertex_attributes=vattrs, path=path,
                    file_format=FileFormat(binary=False))


def _off_colours(vtok: list[list[str]], prefix: str, path: Path) -> dict[str, np.ndarray]:
    """COFF colours: the 3 or 4 values after x y z (and nx ny nz with NOFF)."""
    start = 6 if "N" in prefix else 3
    st = 2 if "ST" in prefix else 0
    n = min(len(t) for t in vtok) - start - st
    if n < 3:
        logger.warning("%s: COFF vertex lines without 3 colour values; colours not kept", path)
        return {}
    n = min(n, 4)
    try:
        C = np.array([t[start:start + n] for t in vtok], dtype=np.float64)
    except ValueError:
        logger.warning("%s: malformed COFF colours; colours not kept", path)
        return {}
    names = ("red", "green", "blue", "alpha")[:n]
    as_int = all("." not in x and "e" not in x.lower() for x in vtok[0][start:start + n])
    if as_int and C.max() <= 255 and C.min() >= 0:
        C = C.astype(np.uint8)
    return {nm: C[:, k].copy() for k, nm in enumerate(names)}


def _write_off(fh: Any, V: np.ndarray, F: np.ndarray, vattrs: dict | None = None) -> None:
    vattrs = vattrs or {}
    rgb = [vattrs.get(c) for c in ("red", "green", "blue")]
    if all(c is not None for c in rgb):
        dt = np.asarray(rgb[0]).dtype
        alpha = vattrs.get("alpha", np.full(len(V), 255 if dt.kind in "iu" else 1.0))
        C = np.stack([np.asarray(c, np.float64) for c in [*rgb, alpha]], axis=1)
        fh.write(f"COFF\n{len(V)} {len(F)} 0\n".encode("ascii"))
        cf = " %d %d %d %d" if dt.kind in "iu" else " %.9g %.9g %.9g %.9g"
        if len(V):
            np.savetxt(fh, np.concatenate([V, C], axis=1), fmt="%.17g %.17g %.17g" + cf)
    else:
        fh.write(f"OFF\n{len(V)} {len(F)} 0\n".encode("ascii"))
        if len(V):
            np.savetxt(fh, V, fmt="%.17g %.17g %.17g")
    if len(F):
        np.savetxt(fh, F, fmt="3 %d %d %d")
