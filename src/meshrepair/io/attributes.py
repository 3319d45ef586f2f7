"""What a mesh file holds besides V and F, and how each format stores it.

:class:`FileFormat` records how a file was stored (binary or ASCII, coordinate precision,
comments). Per-vertex properties are named as in PLY, whatever the format they came from, and
fall into kinds that decide what a repair does with them (:func:`vertex_kind`):

* ``normal``: ``nx, ny, nz``, recomputed for the new geometry (area-weighted face normals);
* ``colour``: ``red, green, blue, alpha`` (and ``diffuse_*``), uchar/ushort or float;
* ``uv``: texture coordinates ``s, t`` / ``u, v`` / ``texture_u, texture_v`` /
  ``texture_s, texture_t``;
* ``float``: any other floating-point property (a quality, a confidence);
* ``label``: any other integer property (a segment id, a flag).

Colours, texture coordinates and floats are interpolated on new vertices; labels take the
value of the nearest original vertex (an average of two labels is no label). Integer colours
are rounded and clipped to their type's range (:func:`cast_back`).

:func:`coordinate_dtype` applies the precision rule of the writers: float32 coordinates are
written as float32 unless rounding to float32 would move a vertex by more than ``1e-3`` mean
edge lengths (then float64, logged).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

logger = logging.getLogger("meshrepair.io")

__all__ = ["FileFormat", "NORMAL_NAMES", "UV_PAIRS", "vertex_kind", "uv_pair", "cast_back",
           "coordinate_dtype", "recompute_normals"]

NORMAL_NAMES = ("nx", "ny", "nz")
COLOUR_NAMES = ("red", "green", "blue", "alpha", "diffuse_red", "diffuse_green",
                "diffuse_blue", "diffuse_alpha")
UV_PAIRS = (("s", "t"), ("u", "v"), ("texture_u", "texture_v"), ("texture_s", "texture_t"))
PRECISION_TOLERANCE = 1e-3
"""Largest float32 rounding of a vertex, in mean edge lengths, for float32 output."""


@dataclass
class FileFormat:
    """How a mesh file stores its data, so that a repaired mesh is written the same way.

    Attributes
    ----------
    binary : bool
        Binary (PLY, STL) or ASCII.
    precision : str
        ``"float32"`` or ``"float64"``: the type of the stored coordinates (text formats:
        ``"float64"``).
    comments : list of str
        PLY ``comment`` lines, kept in order.
    """

    binary: bool = True
    precision: str = "float64"
    comments: list[str] = field(default_factory=list)


def uv_pair(names) -> tuple[str, str] | None:
    """The first texture-coordinate pair whose two names are both in ``names``, or None."""
    have = set(names)
    return next((p for p in UV_PAIRS if p[0] in have and p[1] in have), None)


def vertex_kind(name: str, dtype: np.dtype, names=()) -> str:
    """Kind of a per-vertex property: ``normal``, ``colour``, ``uv``, ``float`` or
    ``label`` (module docstring); ``names`` are all the properties (to pair UV names)."""
    if name in NORMAL_NAMES:
        return "normal"
    if name in COLOUR_NAMES:
        return "colour"
    pair = uv_pair(names)
    if pair is not None and name in pair:
        return "uv"
    return "float" if np.dtype(dtype).kind == "f" else "label"


def cast_back(values: np.ndarray, dtype: np.dtype) -> np.ndarray:
    """Float values in a property's type: rounded and clipped to an integer type's range."""
    dtype = np.dtype(dtype)
    if dtype.kind in "iu":
        info = np.iinfo(dtype)
        return np.clip(np.rint(values), info.min, info.max).astype(dtype)
    if dtype.kind == "b":
        return np.asarray(values) >= 0.5
    return np.asarray(values).astype(dtype)


def recompute_normals(attrs: dict, V: np.ndarray, F: np.ndarray) -> None:
    """Replace ``nx, ny, nz`` in ``attrs`` (if present) by the area-weighted vertex normals of
    (V, F), in the stored dtype."""
    if not all(n in attrs for n in NORMAL_NAMES):
        return
    from meshrepair.mesh.geometry import vertex_normals

    N = vertex_normals(np.asarray(V, np.float64), np.asarray(F, np.int64))
    for k, n in enumerate(NORMAL_NAMES):
        attrs[n] = N[:, k].astype(np.asarray(attrs[n]).dtype)


def coordinate_dtype(V: np.ndarray, F: np.ndarray, precision: str | None, where: str = ""
                     ) -> np.dtype:
    """The dtype to store coordinates in: float64 unless ``precision`` is ``"float32"`` and
    rounding to float32 moves no vertex by more than ``PRECISION_TOLERANCE`` mean edge
    lengths (module docstring)."""
    if precision not in ("float32",):
        return np.dtype(np.float64)
    V = np.asarray(V, np.float64)
    err = float(np.abs(V - V.astype(np.float32)).max()) if len(V) else 0.0
    if err == 0.0:
        return np.dtype(np.float32)
    if len(F):
        e = V[F[:, [1, 2, 0]]] - V[F]
        unit = float(np.linalg.norm(e, axis=2).mean())
    else:
        unit = float(np.linalg.norm(V.max(0) - V.min(0))) if len(V) else 1.0
    if unit > 0 and err <= PRECISION_TOLERANCE * unit:
        return np.dtype(np.float32)
    logger.info("%s: coordinates written as float64: float32 would move them by up to %.3g "
                "mean edge lengths", where, err / unit if unit > 0 else np.inf)
    return np.dtype(np.float64)
