"""Carry a file's attributes over to a repaired mesh: :func:`carry_attributes` (a result is
written like its input with :func:`meshrepair.io.write_like_input`).

Every task keeps the original vertices it does not remove, in their order (``vertex_map``
gives their new index), and the original faces it does not remove; it adds new vertices and
faces. On the result:

* original vertices keep their per-vertex values bit for bit, original faces their per-face
  values and per-corner texture coordinates (matched by their vertex triple);
* normals ``nx, ny, nz`` are recomputed for the new geometry (every vertex);
* on new vertices, colours, texture coordinates and float properties are interpolated from the
  values around the patch by a thin-plate (biharmonic, default) or harmonic fairing
  (:func:`meshrepair.mesh.attributes.harmonic_extend`, where the equations are),
  integer labels take the value of the nearest original vertex
  (:func:`meshrepair.io.attributes.vertex_kind`), a completion template's own per-vertex
  values are used where the template has them;
* new faces take the per-face values and the material of a neighbouring face
  (:func:`meshrepair.mesh.attributes.propagate_faces`);
* per-corner texture coordinates (OBJ ``vt``): the corners of new faces at a border vertex use
  that vertex's texture coordinate; where a border vertex has several (a texture seam crosses
  the patch) the most used one is taken and a warning names the vertices; new vertices get new
  ``vt`` rows interpolated the same way.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.io.attributes import NORMAL_NAMES, cast_back, recompute_normals, vertex_kind
from meshrepair.io.common import MeshData
from meshrepair.io.trimesh_visuals import from_trimesh, is_trimesh, to_trimesh
from meshrepair.mesh.attributes import METHODS, harmonic_extend, nearest_known, propagate_faces

logger = logging.getLogger("meshrepair.io")

__all__ = ["carry_attributes"]


def carry_attributes(source: Any, result: Any, *, template: MeshData | None = None,
                     template_map: np.ndarray | None = None,
                     interpolation: str = "biharmonic") -> Any:
    """The attributes of ``source`` on the repaired mesh ``result`` (module docstring).

    Parameters
    ----------
    source : MeshData or trimesh.Trimesh
        The mesh the task was given, with its attributes (``read_mesh``; a trimesh mesh with
        its colour or texture visuals).
    result : a task result or MeshData
        Anything with ``V``, ``F`` and (for a task that removes or adds vertices)
        ``vertex_map``: :class:`~meshrepair.fill.FillResult`,
        :class:`~meshrepair.complete.CompletionResult`, :class:`~meshrepair.denoise
        .DenoiseResult` (same vertices and faces: no ``vertex_map`` needed).
    template : MeshData, optional
        A completion template with attributes of its own.
    template_map : (k, 2) int array, optional
        Pairs ``(template vertex, result vertex)`` for ``template``.
    interpolation : {"biharmonic", "harmonic"}
        How values on new vertices follow the values around them
        (:mod:`meshrepair.mesh.attributes`).

    Returns
    -------
    MeshData, or trimesh.Trimesh if ``source`` is one
        ``V``, ``F`` of the result with the carried attributes and the source's file format:
        write it with ``write_mesh(path, out.V, out.F, like=out)``.
    """
    if is_trimesh(source):
        material = getattr(getattr(source.visual, "material", None), "copy", lambda: None)()
        return to_trimesh(carry_attributes(from_trimesh(source), result, template=template,
                                           template_map=template_map,
                                           interpolation=interpolation), material=material)
    if interpolation not in METHODS:
        raise MeshRepairError(f"interpolation must be one of {', '.join(METHODS)}, got "
                              f"{interpolation!r}")
    if not isinstance(source, MeshData):
        raise MeshRepairError("carry_attributes needs the source as a MeshData (read_mesh) or a "
                              f"trimesh.Trimesh, got {type(source).__name__}")
    V = np.asarray(result.V, dtype=np.float64)
    F = np.asarray(result.F, dtype=np.int64)
    nV, nF, nV0 = len(V), len(F), len(source.V)
    vmap = getattr(result, "vertex_map", None)
    if vmap is None or len(vmap) == 0:
        if nV < nV0:
            raise MeshRepairError(f"the result has {nV} vertices, fewer than the source's "
                                  f"{nV0}, and no vertex_map: is it the result of this source?")
        vmap = np.arange(nV0)
    vmap = np.asarray(vmap, dtype=np.int64)
    if len(vmap) != nV0 or (vmap >= nV).any():
        raise MeshRepairError(f"result.vertex_map ({len(vmap)} entries) does not fit the source "
                              f"({nV0} vertices) and the result ({nV} vertices)")
    orig = np.full(nV, -1, np.int64)
    orig[vmap[vmap >= 0]] = np.flatnonzero(vmap >= 0)
    known = orig >= 0
    face_src = _match_faces(source.F, F, orig)

    vattrs = _vertex_values(source, V, F, orig, known, template, template_map, interpolation)
    out = MeshData(V=V, F=F, vertex_attributes=vattrs, path=None,
                   materials=list(source.materials),
                   material_libraries=list(source.material_libraries),
                   file_format=source.file_format)
    has = face_src >= 0
    from_face = face_src[np.where(has, np.arange(nF), propagate_faces(F, has))] \
        if nF else face_src
    ok = from_face >= 0
    for name, a in source.face_attributes.items():
        col = np.zeros(nF, dtype=a.dtype)
        col[ok] = a[from_face[ok]]
        out.face_attributes[name] = col
    if source.face_materials is not None:
        out.face_materials = np.where(ok, source.face_materials[np.maximum(from_face, 0)], -1)
    if source.texcoords is not None and source.face_texcoords is not None:
        out.texcoords, out.face_texcoords = _corner_uvs(source, V, F, orig, face_src,
                                                        interpolation)
    return out


def _match_faces(F0: np.ndarray, F: np.ndarray, orig: np.ndarray) -> np.ndarray:
    """Source face of each result face whose three vertices are original and form a source
    face (same vertex set), else -1."""
    src = np.full(len(F), -1, np.int64)
    if len(F) == 0 or len(F0) == 0:
        return src
    G = orig[F]
    cand = np.flatnonzero((G >= 0).all(axis=1))
    if cand.size == 0:
        return src
    both = _keys(np.sort(np.vstack([F0, G[cand]]), axis=1))
    k0, k = both[:len(F0)], both[len(F0):]
    order = np.argsort(k0, kind="stable")
    pos = np.searchsorted(k0[order], k)
    pos = np.minimum(pos, len(k0) - 1)
    hit = k0[order][pos] == k
    src[cand[hit]] = order[pos[hit]]
    return src


def _keys(T: np.ndarray) -> np.ndarray:
    """One comparable key per sorted index triple: ``(a * n + b) * n + c`` in int64 when it
    fits (n < 2**21), else a structured view (slower to sort)."""
    T = np.ascontiguousarray(T, dtype=np.int64)
    n = int(T.max()) + 1 if T.size else 1
    if n < 1 << 21:
        return (T[:, 0] * n + T[:, 1]) * n + T[:, 2]
    return T.view([("a", np.int64), ("b", np.int64), ("c", np.int64)]).ravel()


def _vertex_values(source: MeshData, V: np.ndarray, F: np.ndarray, orig: np.ndarray,
                   known: np.ndarray, template: MeshData | None,
                   template_map: np.ndarray | None, method: str) -> dict[str, np.ndarray]:
    names = list(source.vertex_attributes)
    out: dict[str, np.ndarray] = {}
    groups: dict[tuple[bool, str], list[str]] = {}
    tmap = None if template_map is None or template is None else \
        np.asarray(template_map, np.int64).reshape(-1, 2)
    with_t = known.copy()
    if tmap is not None:
        with_t[tmap[:, 1]] = True
    for name, a in source.vertex_attributes.items():
        a = np.asarray(a)
        col = np.zeros(len(V), dtype=a.dtype)
        col[known] = a[orig[known]]
        from_t = tmap is not None and name in template.vertex_attributes
        if from_t:
            col[tmap[:, 1]] = cast_back(np.asarray(template.vertex_attributes[name])[tmap[:, 0]],
                                        a.dtype)
        out[name] = col
        kind = vertex_kind(name, a.dtype, names)
        if kind != "normal":
            groups.setdefault((from_t, "label" if kind == "label" else "smooth"), []).append(name)
    if tmap is not None:
        missing = [n for n in names if n not in template.vertex_attributes]
        if missing:
            logger.info("the template has no %s: interpolated from the border", missing)
    for (from_t, how), group in groups.items():
        given = with_t if from_t else known
        if given.all():
            continue
        if how == "label":
            near = nearest_known(V, given)
            for n in group:
                out[n][~given] = out[n][near[~given]]
            continue
        X = harmonic_extend(V, F, np.stack([out[n].astype(np.float64) for n in group], 1), given,
                            method)
        for k, n in enumerate(group):
            out[n][~given] = cast_back(X[~given, k], out[n].dtype)
    if all(n in out for n in NORMAL_NAMES):
        recompute_normals(out, V, F)
    return out


def _corner_uvs(source: MeshData, V: np.ndarray, F: np.ndarray, orig: np.ndarray,
                face_src: np.ndarray, method: str) -> tuple[np.ndarray, np.ndarray]:
    """Per-corner texture coordinates of the result: kept faces keep theirs; the corners of
    the other faces use their vertex's (interpolated for new vertices, appended to the table)."""
    T0, TC0 = source.texcoords, source.face_texcoords
    nV, nF = len(V), len(F)
    TC = np.full((nF, 3), -1, np.int64)
    kept = np.flatnonzero(face_src >= 0)
    if kept.size:  # corner j of a kept face: the source corner with the same vertex
        S = source.F[face_src[kept]]
        G = orig[F[kept]]
        for j in range(3):
            at = np.argmax(S == G[:, j:j + 1], axis=1)
            TC[kept, j] = TC0[face_src[kept], at]
    # each vertex's texture coordinate index, from the corners of kept faces around it
    vt_of = np.full(nV, -1, np.int64)
    seam: list[int] = []
    pairs = np.stack([F[kept].ravel(), TC[kept].ravel()], axis=1) if kept.size else \
        np.empty((0, 2), np.int64)
    pairs = pairs[pairs[:, 1] >= 0]
    new_faces = np.flatnonzero(face_src < 0)
    need = np.zeros(nV, bool)
    need[F[new_faces].ravel()] = True
    if len(pairs):
        uniq, counts = np.unique(pairs, axis=0, return_counts=True)
        order = np.lexsort((-counts, uniq[:, 0]))
        uniq, counts = uniq[order], counts[order]
        first = np.r_[True, uniq[1:, 0] != uniq[:-1, 0]]
        vt_of[uniq[first, 0]] = uniq[first, 1]
        # several distinct texture coordinates at a vertex that new faces use: a seam
        vals = T0[uniq[:, 1]]
        head = np.flatnonzero(first)[np.cumsum(first) - 1]  # first row of each vertex's group
        dup = np.abs(vals - vals[head]).max(axis=1) > 0
        seam = sorted({int(v) for v in uniq[dup, 0] if need[v]})
    if seam:
        logger.warning("a texture seam crosses a repaired patch at %d border vertices (first: "
                       "%s): each has several texture coordinates and the new faces use the "
                       "most used one, so the texture may show a discontinuity there",
                       len(seam), seam[:8])
    have = vt_of >= 0
    if not need.any():
        return T0.copy(), TC
    uv = np.zeros((nV, 2))
    uv[have] = T0[vt_of[have]]
    todo = need & ~have
    if todo.any():
        if not have.any():
            logger.warning("no texture coordinates around the new faces: they get none")
        else:
            uv = harmonic_extend(V, F, uv, have, method)
    new_rows = np.flatnonzero(todo) if have.any() else np.empty(0, np.int64)
    vt_of[new_rows] = len(T0) + np.arange(len(new_rows))
    table = np.vstack([T0, uv[new_rows]])
    TC[new_faces] = vt_of[F[new_faces]]
    return table, TC
