"""Common pieces of the mesh readers and writers: :class:`MeshData`, the file checks every
reader makes first, the parse-error type and the helpers several formats share (text decoding,
float parsing, fan triangulation of polygons, face index and header-count checks)."""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.io.attributes import FileFormat

logger = logging.getLogger("meshrepair.io")


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
        Per-vertex scalar properties by their PLY names, dtype as stored: colours ``red,
        green, blue[, alpha]`` (uchar or float), normals ``nx, ny, nz``, texture coordinates
        (``s, t`` / ``u, v`` / ``texture_u, texture_v``) and any custom property (a mask, a
        quality). OBJ vertex colours (``v x y z r g b``) and normals (``vn``) and OFF colours
        (``COFF``) are given under the same names.
    path : pathlib.Path or None
        The file the mesh was read from.
    face_attributes : dict of str to (nF,) ndarray
        Per-face scalar properties (PLY), one value per triangle (a fan-triangulated polygon
        repeats its value).
    texcoords : (nT, 2) float64 or None
        Texture coordinate table (OBJ ``vt``; PLY face ``texcoord`` lists).
    face_texcoords : (nF, 3) int64 or None
        Per-corner index into ``texcoords``, -1 for a corner without one.
    face_materials : (nF,) int64 or None
        Index into ``materials`` of each face's material (OBJ ``usemtl``), -1 for none.
    materials : list of str
        Material names, in order of first use.
    material_libraries : list of str
        OBJ ``mtllib`` file names, as written in the file (the files are never touched).
    file_format : FileFormat or None
        How the file was stored (binary or ASCII, coordinate precision, comments); writers
        follow it when given the mesh as ``like`` (:func:`meshrepair.io.write_mesh`).
    """

    V: np.ndarray
    F: np.ndarray
    vertex_attributes: dict[str, np.ndarray] = field(default_factory=dict)
    path: Path | None = None
    face_attributes: dict[str, np.ndarray] = field(default_factory=dict)
    texcoords: np.ndarray | None = None
    face_texcoords: np.ndarray | None = None
    face_materials: np.ndarray | None = None
    materials: list[str] = field(default_factory=list)
    material_libraries: list[str] = field(default_factory=list)
    file_format: FileFormat | None = None

    @property
    def n_vertices(self) -> int:
        """Number of vertices."""
        return int(self.V.shape[0])

    @property
    def n_faces(self) -> int:
        """Number of faces."""
        return int(self.F.shape[0])



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


def _undercount(what: str, where: str = "") -> _Bad:
    """The error for data after what a header declares: ``what`` says what was declared and
    what follows; ``where`` (e.g. ``"from line 7: "``) starts the parenthesis."""
    return _Bad(f"{what} ({where}the header undercounts, or the file is corrupt); refusing to "
                "drop data silently")
