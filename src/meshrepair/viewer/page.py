"""The self-contained 3-D viewer page: meshes packed as binary, three.js carried as a module.

Layout of the page (one HTML file, opens offline from disk, no server, no network):

* ``<script type="importmap">`` maps the specifier ``"three"`` to a ``data:text/javascript;base64``
  URL of the vendored bundle ``vendor/three.bundle.min.js`` (three.js r187 from npm plus its
  ``OrbitControls``, bundled once with esbuild, see ``vendor/README.md``). three.js is ESM-only,
  and an import map is the standard way to hand a module to ``import ... from "three"``
  without a server.
* ``<script type="application/json" id="mr-viewer-data">``: the meshes. Each mesh is a
  ``float32`` little-endian position array ``(nV, 3)`` and a ``uint32`` index array ``(nF, 3)``,
  base64-encoded (12 bytes per vertex and per face before base64's 4/3); per-vertex scalars are
  ``float32``, highlighted faces and sharp edges ``uint32`` indices.
* ``viewer.js`` (module script, hand-written, next to this file) builds one WebGL canvas per
  mesh; the panes' cameras are kept equal (orbit, pan, zoom) by copying the moved camera and
  its target to the others on every change.

Meshes above ``face_budget`` faces are shown as a vertex-clustering copy
(:mod:`meshrepair.viewer.decimate`), and the pane says so.
"""

from __future__ import annotations

import base64
import html
import json
import logging
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from meshrepair.errors import MeshRepairError
from meshrepair.render.framing import Frame
from meshrepair.viewer.decimate import cluster_decimate

__all__ = ["DEFAULT_FACE_BUDGET", "ViewerMesh", "viewer_page", "viewer_section", "write_viewer"]

log = logging.getLogger(__name__)

#: faces per pane above which the page shows a decimated copy (the whole page stays < ~15 MB
#: for two panes: 12 bytes per face and ~6 per vertex, times 4/3 for base64)
DEFAULT_FACE_BUDGET = 300_000
_MAX_PANES = 8  # browsers allow ~16 WebGL contexts per page
_MAX_CATEGORIES = 12
_MASK_LUT = np.array([[204, 204, 209], [242, 115, 26]], np.uint8)  # 0: grey, 1: orange


@dataclass
class ViewerMesh:
    """One pane of the viewer.

    Attributes
    ----------
    title : str
    V : (nV, 3) float
    F : (nF, 3) int
    scalars : dict of str to (nV,) float
        Per-vertex values the user can colour by (e.g. ``"mean curvature"``, ``"filled"``).
        Values that are at most 12 distinct integers are coloured by category.
    highlight : (nF,) bool, optional
        Faces to highlight (filled, inpainted or template faces).
    highlight_label : str
        What the highlighted faces are (shown next to the toggle).
    sharp_edges : (k, 2) int, optional
        Vertex pairs of the sharp edges (``M_E``) to overlay.
    """

    title: str
    V: np.ndarray
    F: np.ndarray
    scalars: dict = field(default_factory=dict)
    highlight: np.ndarray | None = None
    highlight_label: str = "filled faces"
    sharp_edges: np.ndarray | None = None


def _fmt(v: object) -> str:
    """Readable text for a table cell (numbers with 6 significant digits)."""
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, bool) or v is None:
        return str(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, np.ndarray):
        if v.size <= 8:
            return np.array2string(v, precision=6, separator=", ")
        return f"array of shape {v.shape}, dtype {v.dtype}"
    if isinstance(v, Mapping):
        return ", ".join(f"{k}={_fmt(x)}" for k, x in v.items())
    if isinstance(v, (list, tuple)):
        inner = ", ".join(_fmt(x) for x in v)
        return f"[{inner}]" if isinstance(v, list) else f"({inner})"
    return str(v)


def _b64(a: np.ndarray, dtype: str) -> str:
    return base64.b64encode(np.ascontiguousarray(a, dtype=dtype).tobytes()).decode("ascii")


def _asset(name: str) -> str:
    return resources.files(__package__).joinpath(name).read_text(encoding="utf-8")


def _three_data_url() -> str:
    raw = resources.files(__package__).joinpath("vendor/three.bundle.min.js").read_bytes()
    return "data:text/javascript;base64," + base64.b64encode(raw).decode("ascii")


def _check(m: ViewerMesh, i: int) -> tuple[np.ndarray, np.ndarray]:
    V = np.asarray(m.V, dtype=np.float64)
    F = np.asarray(m.F)
    if V.ndim != 2 or V.shape[1] != 3 or F.ndim != 2 or F.shape[1] != 3 or len(F) == 0:
        raise MeshRepairError(f"viewer mesh {i} ({m.title!r}) must be V (nV, 3) and F (nF, 3) "
                              f"with at least one face; got {V.shape} and {F.shape}")
    if not np.issubdtype(F.dtype, np.integer) or F.min() < 0 or F.max() >= len(V):
        raise MeshRepairError(f"viewer mesh {i} ({m.title!r}): face indices out of range")
    if not np.all(np.isfinite(V)):
        raise MeshRepairError(f"viewer mesh {i} ({m.title!r}): vertex coordinates are not finite")
    return V, F.astype(np.int64)


def _scalar_specs(meshes: Sequence[ViewerMesh]) -> dict:
    """Colour range and look-up table of each scalar name (one range over all panes)."""
    from meshrepair.render import _lut, _robust_range

    names: list[str] = []
    for m in meshes:
        names += [k for k in m.scalars if k not in names]
    specs = {}
    for name in names:
        vals = np.concatenate([np.asarray(m.scalars[name], np.float64).ravel()
                               for m in meshes if name in m.scalars])
        fin = vals[np.isfinite(vals)]
        cats = np.unique(fin)
        if 0 < cats.size <= _MAX_CATEGORIES and np.all(cats == np.round(cats)):
            if cats.size <= 2 and np.all(np.isin(cats, (0.0, 1.0))):
                colours = _MASK_LUT[cats.astype(int)]
            else:
                import matplotlib

                cm = matplotlib.colormaps["tab10" if cats.size <= 10 else "tab20"]
                colours = (np.asarray(cm(np.arange(cats.size)))[:, :3] * 255 + 0.5).astype(
                    np.uint8)
            specs[name] = {"categories": [float(c) for c in cats],
                           "colors": [[int(x) for x in c] for c in colours]}
            continue
        curv = "curvature" in name.lower()
        lo, hi = _robust_range(fin if fin.size else np.zeros(1), (2.0, 98.0), symmetric=curv)
        lut = (_lut("coolwarm" if curv else "viridis") * 255 + 0.5).astype(np.uint8)
        specs[name] = {"lo": lo, "hi": hi, "lut": _b64(lut, "uint8")}
    return specs


def _pack(meshes: Sequence[ViewerMesh], face_budget: int) -> tuple[list[dict], np.ndarray]:
    panes = []
    allpts = []
    for i, m in enumerate(meshes):
        V, F = _check(m, i)
        allpts += [V.min(axis=0), V.max(axis=0)]
        d = cluster_decimate(V, F, face_budget)
        pane: dict = {"title": str(m.title), "nV": len(V), "nF": len(F),
                      "positions": _b64(d.V, "<f4"), "indices": _b64(d.F, "<u4"),
                      "shownV": len(d.V), "shownF": len(d.F), "decimated": d.decimated}
        sc = {}
        for name, vals in m.scalars.items():
            v = np.asarray(vals, dtype=np.float64).ravel()
            if v.shape[0] != len(V):
                raise MeshRepairError(f"scalar {name!r} of viewer mesh {i} has {v.shape[0]} "
                                      f"values for {len(V)} vertices; pass one per vertex")
            fin = v[np.isfinite(v)]
            is_cat = fin.size and np.all(fin == np.round(fin)) and np.unique(fin).size <= 12
            sc[str(name)] = _b64(d.vertex_values(v, reduce="max" if is_cat else "mean"), "<f4")
        pane["scalars"] = sc
        if m.highlight is not None:
            h = np.asarray(m.highlight).ravel()
            if h.shape[0] != len(F):
                raise MeshRepairError(f"highlight of viewer mesh {i} has {h.shape[0]} entries "
                                      f"for {len(F)} faces")
            h = h.astype(bool)[d.face_origin]
            pane["highlight"] = _b64(np.flatnonzero(h), "<u4")
            pane["highlightCount"] = int(np.count_nonzero(np.asarray(m.highlight)))
            pane["highlightLabel"] = str(m.highlight_label)
        if m.sharp_edges is not None:
            e = np.asarray(m.sharp_edges, dtype=np.int64).reshape(-1, 2)
            if len(e) and (e.min() < 0 or e.max() >= len(V)):
                raise MeshRepairError(f"sharp edges of viewer mesh {i} index missing vertices")
            pane["sharp"] = _b64(d.edges(e), "<u4")
            pane["sharpCount"] = int(len(e))
        panes.append(pane)
    return panes, np.array(allpts)


def _json_for_script(obj: object) -> str:
    """JSON safe inside a ``<script>`` element (no ``</`` or ``<!--``)."""
    return (json.dumps(obj, separators=(",", ":"), allow_nan=False)
            .replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026"))


def viewer_section(
    meshes: Sequence[ViewerMesh],
    regions: Sequence[Frame] | None = None,
    *,
    face_budget: int = DEFAULT_FACE_BUDGET,
    height: int = 440,
    region_details: Sequence[str] | None = None,
) -> str:
    """HTML fragment of the viewer (import map, data, container, module script).

    Parameters
    ----------
    meshes : list of ViewerMesh
        One pane each (1 to 8).
    regions : list of Frame, optional
        Holes or regions listed with a "go to" button that frames each (original coordinates).
    face_budget : int
        Faces per pane above which a vertex-clustering copy is shown (and the pane says so).
    height : int
        Height of each pane in CSS pixels.
    region_details : list of str, optional
        One text per region (e.g. "filled (plane; 12 vertices, 20 faces)").

    Returns
    -------
    str
        Insert it once into a page's ``<body>`` (the import map must precede module scripts).
    """
    if not 1 <= len(meshes) <= _MAX_PANES:
        raise MeshRepairError(f"the viewer shows 1 to {_MAX_PANES} meshes, got {len(meshes)}")
    if not 120 <= int(height) <= 4000:
        raise MeshRepairError(f"viewer pane height must be 120..4000 pixels, got {height}")
    regions = list(regions or [])
    if region_details is not None and len(region_details) != len(regions):
        raise MeshRepairError("region_details needs one text per region")
    panes, pts = _pack(meshes, face_budget)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    mid = 0.5 * (lo + hi)
    rad = max(float(np.sqrt(((np.asarray(m.V, np.float64) - mid) ** 2).sum(axis=1).max()))
              for m in meshes)
    data = {
        "version": 1,
        "panes": panes,
        "scalars": _scalar_specs(meshes),
        "regions": [{**r.as_dict(), "detail": (str(region_details[k]) if region_details
                                               else "")} for k, r in enumerate(regions)],
        "scene": {"center": [float(x) for x in mid], "radius": max(rad, 1e-9)},
        "height": int(height),
        "faceBudget": int(face_budget),
    }
    imports = json.dumps({"imports": {"three": _three_data_url()}})
    return "\n".join([
        f'<script type="importmap">{imports}</script>',
        f"<style>\n{_asset('viewer.css')}\n</style>",
        '<div class="mr-viewer" id="mr-viewer"><p class="mr-status">Loading the 3-D viewer '
        "(needs JavaScript and WebGL)...</p></div>",
        f'<script type="application/json" id="mr-viewer-data">{_json_for_script(data)}</script>',
        f'<script type="module">\n{_asset("viewer.js")}\n</script>',
    ])


def viewer_page(
    meshes: Sequence[ViewerMesh],
    regions: Sequence[Frame] | None = None,
    *,
    title: str = "meshrepair viewer",
    metrics: Mapping[str, Sequence[object]] | None = None,
    face_budget: int = DEFAULT_FACE_BUDGET,
    height: int = 520,
    region_details: Sequence[str] | None = None,
) -> str:
    """A whole HTML page: the viewer, the region list and a metrics table.

    ``metrics`` maps a metric name to one value per mesh (shown as a table, one column per
    mesh). Other parameters as :func:`viewer_section`.
    """
    parts = [viewer_section(meshes, regions, face_budget=face_budget, height=height,
                            region_details=region_details)]
    if metrics:
        head = "".join(f"<th>{html.escape(str(m.title))}</th>" for m in meshes)
        rows = [f"<tr><th>metric</th>{head}</tr>"]
        for name, vals in metrics.items():
            vals = list(vals)
            if len(vals) != len(meshes):
                raise MeshRepairError(f"metric {name!r} needs one value per mesh")
            cells = "".join(f'<td class="num">{html.escape(_fmt(v))}</td>' for v in vals)
            rows.append(f"<tr><td>{html.escape(str(name))}</td>{cells}</tr>")
        parts.append('<h2>Metrics</h2>\n<table class="mr-metrics">' + "\n".join(rows)
                     + "</table>")
    body = "\n".join(parts)
    t = html.escape(title)
    return (f'<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
            f"<title>{t}</title>\n<style>\n{_asset('page.css')}\n</style>\n</head>\n<body>\n"
            f"<h1>{t}</h1>\n{body}\n</body>\n</html>\n")


def write_viewer(path: str | os.PathLike, meshes: Sequence[ViewerMesh],
                 regions: Sequence[Frame] | None = None, **kw) -> Path:
    """Write :func:`viewer_page` to ``path`` (atomically); keywords as :func:`viewer_page`."""
    page = viewer_page(meshes, regions, **kw)
    from meshrepair.atomic import atomic_write

    p = Path(path)
    with atomic_write(p, "w") as fh:
        fh.write(page)
    log.info("wrote viewer %s (%.1f MB)", p, len(page) / 2**20)
    return p
