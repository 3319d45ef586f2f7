"""Completion arguments from the files a user names (the ``complete`` command and batch jobs):
the template (a mesh, a piece of a mesh, or the mirror image), the region (a face list or a
per-vertex mask file) and the per-vertex attributes written with a PLY output."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.io.masks import read_face_selection

_MASK_SUFFIXES = (".ply", ".npy")


def _selection(path: str, V: np.ndarray, F: np.ndarray) -> dict:
    """``{"region": faces}`` or ``{"region_vertices": mask}`` from a selection file."""
    if Path(path).suffix.lower() in _MASK_SUFFIXES:
        from meshrepair.io.masks import read_vertex_mask

        return {"region_vertices": read_vertex_mask(path, len(V))}
    return {"region": read_face_selection(path, len(F))}


def complete_arguments(mesh, tmesh, options: dict) -> tuple:
    """``(template, kw)`` for :func:`meshrepair.complete` from the read meshes (``tmesh`` None
    with ``mirror``) and :func:`complete_options`' values (selection files are read here)."""
    from meshrepair.complete.api import extract_patch

    kw = dict(options)
    region, hole, template_region = kw.pop("region"), kw.pop("hole"), kw.pop("template_region")
    mirror = bool(kw.pop("mirror", False))
    if mirror:
        if template_region is not None or kw.get("transform") is not None:
            raise MeshRepairError("--mirror finds the template itself: drop --template-region "
                                  "and --transform")
        template = "mirror"
    elif tmesh is None:
        raise MeshRepairError("complete needs a template mesh (or --mirror)")
    elif template_region is not None:
        sel = _selection(template_region, tmesh.V, tmesh.F)
        if "region" in sel:
            faces = sel["region"]
        else:
            faces = np.flatnonzero(sel["region_vertices"][tmesh.F].all(axis=1))
            if faces.size == 0:
                raise MeshRepairError("--template-region selects no face of the template")
        extract_patch(tmesh.V, tmesh.F, faces)  # a clear error for an empty/invalid selection
        # a piece of a mesh: its context rings around the selection take part in the alignment
        template = (tmesh.V, tmesh.F, faces)
    else:
        template = (tmesh.V, tmesh.F)
    if region is not None:
        kw.update(_selection(region, mesh.V, mesh.F))
    elif hole is not None:
        kw["hole"] = hole
    else:
        raise MeshRepairError("complete needs --region FILE or --hole K")
    return template, kw


def output_attributes(res, out: str | Path) -> dict | None:
    """Per-vertex m_v, strip and template attributes written with a PLY output (else None)."""
    if Path(out).suffix.lower() != ".ply":
        return None
    nV = len(res.V)
    strip = np.zeros(nV, np.uint8)
    strip[res.strip_vertices] = 1
    tmpl = np.zeros(nV, np.uint8)
    tmpl[res.template_vertices] = 1
    return {"m_v": res.M_V.astype(np.float32), "strip": strip, "template": tmpl}
