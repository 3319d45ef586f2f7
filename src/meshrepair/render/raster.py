"""The renderer's vectorised numpy z-buffer rasteriser, shading and edge overlays.

The rasteriser enumerates, for every triangle, the pixel centres inside its screen bounding box
(in chunks of about a million candidates), keeps those with non-negative barycentric coordinates
and resolves visibility with ``np.minimum.at`` on a depth buffer, which gives exact per-pixel
occlusion. Shading, colour mapping and overlays are then computed once per *pixel* from the
stored face index and barycentric coordinates, so the cost is ``O(nF + covered pixels)`` array
operations. Shading is Lambertian with a head light (light along the view direction), two-sided
so open scans seen from behind stay visible; ``flat`` uses per-face normals and ``smooth``
interpolates vertex normals per pixel (Phong normal interpolation). Overlay edges are sampled
every half pixel and drawn where they are not hidden by the surface (depth test with a
tolerance of three pixel sizes).
"""

from __future__ import annotations

import numpy as np

from meshrepair.mesh.geometry import face_normals_areas, vertex_normals
from meshrepair.render.camera import _project
from meshrepair.render.colour import _BASE_GREY, _NAN_GREY, _lut

_CHUNK = 1 << 20  # candidate (triangle, pixel) pairs processed at once
_REGION_BLUE = np.array([0.20, 0.42, 0.95])
_EDGE_COLOUR = np.array([0.05, 0.05, 0.05])
_AMBIENT = 0.18


def _rasterize(
    xyz: np.ndarray, F: np.ndarray, width: int, height: int, near: float = -np.inf
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Z-buffer rasterisation of projected triangles.

    Parameters
    ----------
    xyz : (nV, 3) screen coordinates and depth (see :func:`_project`)
    F : (nF, 3) int64
    near : float
        Pixels with depth below ``near`` (nearer the camera) are clipped away.

    Returns
    -------
    face : (H*W,) int64, visible face per pixel or -1
    b1, b2 : (H*W,) float64, barycentric coordinates of vertices 1 and 2 of that face
    zbuf : (H*W,) float64, depth per pixel (inf = background)
    """
    npx = width * height
    zbuf = np.full(npx, np.inf)
    fbuf = np.full(npx, -1, dtype=np.int64)
    b1buf = np.zeros(npx)
    b2buf = np.zeros(npx)

    P = xyz[F]  # (nF, 3 corners, 3)
    x0, y0, z0 = P[:, 0, 0], P[:, 0, 1], P[:, 0, 2]
    ex1, ey1, ez1 = P[:, 1, 0] - x0, P[:, 1, 1] - y0, P[:, 1, 2] - z0
    ex2, ey2, ez2 = P[:, 2, 0] - x0, P[:, 2, 1] - y0, P[:, 2, 2] - z0
    area2 = ex1 * ey2 - ex2 * ey1
    # pixel centres at (i + 0.5, j + 0.5): candidate columns/rows inside the triangle's bbox
    xmin = np.ceil(P[:, :, 0].min(axis=1) - 0.5)
    xmax = np.floor(P[:, :, 0].max(axis=1) - 0.5)
    ymin = np.ceil(P[:, :, 1].min(axis=1) - 0.5)
    ymax = np.floor(P[:, :, 1].max(axis=1) - 0.5)
    xmin, ymin = np.maximum(xmin, 0), np.maximum(ymin, 0)
    xmax, ymax = np.minimum(xmax, width - 1), np.minimum(ymax, height - 1)
    bw = (xmax - xmin + 1).astype(np.int64)
    bh = (ymax - ymin + 1).astype(np.int64)
    keep = (bw > 0) & (bh > 0) & (np.abs(area2) > 1e-12)
    tri = np.flatnonzero(keep)
    if tri.size == 0:
        return fbuf, b1buf, b2buf, zbuf
    bw, bh = bw[tri], bh[tri]
    inv = 1.0 / area2[tri]
    # barycentrics and depth as affine functions a*px + b*py + c of the pixel centre (px, py):
    # b1 = (dx*ey2 - dy*ex2)/area2, b2 = (dy*ex1 - dx*ey1)/area2 with dx = px - x0, dy = py - y0
    cx, cy = 0.5 - x0[tri], 0.5 - y0[tri]  # pixel centre offset folded into the constant
    a1, q1 = ey2[tri] * inv, -ex2[tri] * inv
    a2, q2 = -ey1[tri] * inv, ex1[tri] * inv
    bary = np.stack([a1, q1, a1 * cx + q1 * cy, a2, q2, a2 * cx + q2 * cy], axis=1)
    za, zq = a1 * ez1[tri] + a2 * ez2[tri], q1 * ez1[tri] + q2 * ez2[tri]
    depth = np.stack([za, zq, z0[tri] + za * cx + zq * cy], axis=1)
    xmin_i, ymin_i = xmin[tri].astype(np.int64), ymin[tri].astype(np.int64)
    counts = bw * bh
    ends = np.cumsum(counts)
    eps = -1e-9
    start_t = 0
    while start_t < tri.size:
        base = ends[start_t - 1] if start_t else 0
        stop_t = int(np.searchsorted(ends, base + _CHUNK, side="right"))
        stop_t = max(stop_t, start_t + 1)
        cnt = counts[start_t:stop_t]
        total = int(cnt.sum())
        local = np.repeat(np.arange(start_t, stop_t), cnt)
        offs = np.arange(total) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        w = bw[local]
        py, px = np.divmod(offs, w)
        px += xmin_i[local]
        py += ymin_i[local]
        c = bary[local]
        fx, fy = px.astype(np.float64), py.astype(np.float64)
        b1 = c[:, 0] * fx + c[:, 1] * fy + c[:, 2]
        b2 = c[:, 3] * fx + c[:, 4] * fy + c[:, 5]
        inside = (b1 >= eps) & (b2 >= eps) & (b1 + b2 <= 1.0 - eps)
        if np.any(inside):
            li = local[inside]
            b1, b2, fx, fy = b1[inside], b2[inside], fx[inside], fy[inside]
            d = depth[li]
            z = d[:, 0] * fx + d[:, 1] * fy + d[:, 2]
            pid = py[inside] * width + px[inside]
            if near > -np.inf:
                front = z >= near
                li, b1, b2, z, pid = li[front], b1[front], b2[front], z[front], pid[front]
            np.minimum.at(zbuf, pid, z)
            win = z <= zbuf[pid]
            pw = pid[win]
            fbuf[pw] = tri[li[win]]
            b1buf[pw] = b1[win]
            b2buf[pw] = b2[win]
        start_t = stop_t
    return fbuf, b1buf, b2buf, zbuf


def _draw_edges(
    rgb: np.ndarray,
    xyz: np.ndarray,
    edges: np.ndarray,
    zbuf: np.ndarray,
    width: int,
    height: int,
    *,
    tol: float,
    thickness: int,
    near: float = -np.inf,
) -> None:
    """Draw depth-tested line segments (in place) into ``rgb`` of shape ``(H*W, 3)``."""
    if len(edges) == 0:
        return
    a, b = xyz[edges[:, 0]], xyz[edges[:, 1]]
    length = np.hypot(b[:, 0] - a[:, 0], b[:, 1] - a[:, 1])
    n = np.ceil(2.0 * length).astype(np.int64) + 1  # samples every half pixel
    e = np.repeat(np.arange(len(edges)), n)
    k = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
    t = (k / np.maximum(n - 1, 1)[e])[:, None]
    p = a[e] * (1.0 - t) + b[e] * t
    ix = np.floor(p[:, 0]).astype(np.int64)
    iy = np.floor(p[:, 1]).astype(np.int64)
    ok = (ix >= 0) & (ix < width) & (iy >= 0) & (iy < height)
    ix, iy, z = ix[ok], iy[ok], p[ok, 2]
    vis = (z <= zbuf[iy * width + ix] + tol) & (z >= near)
    ix, iy = ix[vis], iy[vis]
    for ox in range(thickness):
        for oy in range(thickness):
            jx = np.clip(ix + ox - thickness // 2, 0, width - 1)
            jy = np.clip(iy + oy - thickness // 2, 0, height - 1)
            rgb[jy * width + jx] = _EDGE_COLOUR



def _raster(
    V: np.ndarray,
    F: np.ndarray,
    *,
    values: np.ndarray | None,
    vmin: float,
    vmax: float,
    cmap: str,
    shading: str,
    edges: np.ndarray | None,
    face_highlight: np.ndarray | None,
    axes: np.ndarray,
    window: np.ndarray,
    width: int,
    height: int,
    supersample: int,
    near: float = -np.inf,
    categories: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """Render the mesh alone into a float ``(H, W, 3)`` image in ``[0, 1]``.

    ``categories``: (values ``(k,)``, colours ``(k, 3)``): draw each pixel in the colour of the
    category of its nearest vertex (or its face), no interpolation between categories.
    """
    s = supersample
    W, H = width * s, height * s
    xyz, world_per_px = _project(V, axes, window, W, H)
    fbuf, b1, b2, zbuf = _rasterize(xyz, F, W, H, near=near)
    rgb = np.ones((W * H, 3))
    hit = np.flatnonzero(fbuf >= 0)
    f = fbuf[hit]
    w1, w2 = b1[hit, None], b2[hit, None]
    w0 = 1.0 - w1 - w2
    if shading == "flat":
        n = face_normals_areas(V, F)[0][f]
    else:
        vn = vertex_normals(V, F)
        n = w0 * vn[F[f, 0]] + w1 * vn[F[f, 1]] + w2 * vn[F[f, 2]]
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    shade = _AMBIENT + (1.0 - _AMBIENT) * np.abs(n @ axes[2])
    if values is None:
        base = np.broadcast_to(_BASE_GREY, (len(hit), 3)).copy()
    elif categories is not None:
        if len(values) == len(V):
            nearest = np.argmax(np.concatenate([w0, w1, w2], axis=1), axis=1)
            val = values[F[f, nearest]]
        else:
            val = values[f]
        cats, colours = categories
        k = np.clip(np.searchsorted(cats, val), 0, len(cats) - 1)
        base = colours[k].copy()
        base[~(cats[k] == val)] = _NAN_GREY
    else:
        if len(values) == len(V):
            val = (
                w0[:, 0] * values[F[f, 0]] + w1[:, 0] * values[F[f, 1]] + w2[:, 0] * values[F[f, 2]]
            )
        else:
            val = values[f]
        lut = _lut(cmap)
        t = (val - vmin) / (vmax - vmin)
        good = np.isfinite(t)
        idx = np.clip(np.nan_to_num(t) * 255.0 + 0.5, 0, 255).astype(np.int64)
        base = lut[idx]
        base[~good] = _NAN_GREY
    if face_highlight is not None:
        hl = face_highlight[f]
        base[hl] = 0.35 * base[hl] + 0.65 * _REGION_BLUE
    rgb[hit] = base * shade[:, None]
    if edges is not None and len(edges):
        _draw_edges(
            rgb, xyz, edges, zbuf, W, H,
            tol=3.0 * world_per_px, thickness=max(1, round(s * max(width, height) / 500)),
            near=near,
        )  # fmt: skip
    img = rgb.reshape(H, W, 3)
    if s > 1:
        img = img.reshape(height, s, width, s, 3).mean(axis=(1, 3))
    return img


def _to_uint8(img: np.ndarray) -> np.ndarray:
    return np.clip(np.rint(img * 255.0), 0, 255).astype(np.uint8)

