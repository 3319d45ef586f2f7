"""PNG output of the renderer: :func:`save_png` (atomic) and :func:`render_to_file`."""

from __future__ import annotations

import logging
import os
from pathlib import Path

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.render.mesh import render_mesh
from meshrepair.render.raster import _to_uint8

log = logging.getLogger("meshrepair.render")

def save_png(path: str | os.PathLike, image: np.ndarray, *, overwrite: bool = True) -> Path:
    """Write an image as PNG, atomically (:func:`meshrepair.atomic.atomic_write`).

    Parameters
    ----------
    path : str or path-like
        Output file (parent directories are created).
    image : (H, W, 3) or (H, W, 4) uint8, or float in [0, 1]
    overwrite : bool
        If False, refuse to replace an existing file.

    Returns
    -------
    Path
        The written path.
    """
    from matplotlib.image import imsave

    img = np.asarray(image)
    if img.ndim != 3 or img.shape[2] not in (3, 4):
        raise MeshRepairError(f"image must have shape (H, W, 3) or (H, W, 4), got {img.shape}")
    if img.dtype != np.uint8:
        if not np.issubdtype(img.dtype, np.floating):
            raise MeshRepairError(f"image must be uint8 or float in [0, 1], got {img.dtype}")
        img = _to_uint8(img)
    from meshrepair.atomic import atomic_write

    p = Path(path)
    with atomic_write(p, "wb", overwrite=overwrite, make_parents=True) as fh:
        imsave(fh, img, format="png")
    log.info("wrote %s (%d x %d)", p, img.shape[1], img.shape[0])
    return p


def render_to_file(path: str | os.PathLike, V: np.ndarray, F: np.ndarray, **kw) -> np.ndarray:
    """Render with :func:`render_mesh` (keyword options ``kw``) and save as PNG to ``path``.

    Returns
    -------
    (H, W, 3) uint8
        The image.
    """
    img = render_mesh(V, F, **kw)
    save_png(path, img)
    return img

