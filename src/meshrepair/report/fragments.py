"""HTML fragments of the report page (:mod:`meshrepair.report`): the inline style sheet, escaped
text, table cells, embedded PNG figures (``data:`` URIs), the per-hole table and the summary of
the solver history (energy (6) and rule (35)'s relative change, first and last values).
"""

from __future__ import annotations

import base64
import html
import io
import math
from collections.abc import Mapping, Sequence

import numpy as np

from meshrepair.report.convergence_plot import _is_number
from meshrepair.viewer.page import _fmt  # noqa: F401  (the page's table cells)

_CSS = """
body { font-family: -apple-system, 'Segoe UI', Helvetica, Arial, sans-serif; margin: 2em auto;
       max-width: 1200px; color: #222; padding: 0 1em; }
h1 { font-size: 1.6em; border-bottom: 2px solid #ccc; padding-bottom: .3em; }
h2 { font-size: 1.25em; margin-top: 1.8em; }
table { border-collapse: collapse; margin: .5em 0 1em 0; font-size: .95em; }
th, td { border: 1px solid #ccc; padding: .3em .8em; text-align: left; vertical-align: top; }
th { background: #f2f2f2; }
td.num { text-align: right; font-family: Menlo, Consolas, monospace; }
figure { display: inline-block; margin: .5em 1em .5em 0; vertical-align: top; }
figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: .9em; color: #555; margin-top: .3em; }
p.note { color: #666; font-style: italic; }
""".strip()

_HISTORY_KEYS = ("iter", "energy", "rel_change", "res_t", "res_N", "time", "stage")


def _esc(x: object) -> str:
    return html.escape(str(x), quote=True)


def _png_bytes(image: np.ndarray) -> bytes:
    from matplotlib.image import imsave

    buf = io.BytesIO()
    imsave(buf, np.asarray(image), format="png")
    return buf.getvalue()


def _data_uri(png: bytes) -> str:
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def _img(png: bytes, alt: str, caption: str | None = None) -> str:
    cap = f"<figcaption>{_esc(caption)}</figcaption>" if caption else ""
    return f'<figure><img src="{_data_uri(png)}" alt="{_esc(alt)}">{cap}</figure>'


def _table(rows: Sequence[tuple[object, object]], header: tuple[str, str]) -> str:
    out = ["<table>", f"<tr><th>{_esc(header[0])}</th><th>{_esc(header[1])}</th></tr>"]
    for k, v in rows:
        cls = ' class="num"' if _is_number(v) else ""
        out.append(f"<tr><td>{_esc(k)}</td><td{cls}>{_esc(_fmt(v))}</td></tr>")
    out.append("</table>")
    return "\n".join(out)

def hole_table(holes: Sequence[Mapping]) -> str:
    """HTML table of per-hole records: what happened to each hole and why."""
    if not holes:
        return '<p class="note">The mesh had no holes.</p>'
    cols = [("index", "hole"), ("n_boundary", "boundary edges"), ("length", "length"),
            ("status", "status"), ("reason", "how / why"), ("n_new_vertices", "new vertices"),
            ("n_new_faces", "new faces"), ("n_intersections", "intersections"),
            ("seam", "seam° (surround°)"), ("curvature_ratio", "curvature / surround's"),
            ("check", "check"), ("note", "note")]
    out = ["<table>", "<tr>" + "".join(f"<th>{_esc(h)}</th>" for _, h in cols) + "</tr>"]
    for rec in holes:
        rec = dict(rec) if isinstance(rec, Mapping) else dict(rec.as_dict())
        q = rec.get("quality") or {}
        if q:  # the per-hole read-out of meshrepair.fill.quality
            rec["seam"] = f"{q['seam_deg']:.1f} ({q['surround_deg']:.1f})"
            rec["curvature_ratio"] = q["curvature_ratio"]
            rec["check"] = q.get("why") or "-"
        cells = []
        for key, _ in cols:
            v = rec.get(key, "")
            if key == "n_intersections" and _is_number(v) and v < 0:
                v = "not checked"
            cls = ' class="num"' if _is_number(v) else ""
            cells.append(f"<td{cls}>{_esc(_fmt(v))}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</table>")
    counts: dict[str, int] = {}
    for rec in holes:
        st = str((rec if isinstance(rec, Mapping) else rec.as_dict()).get("status", "?"))
        counts[st] = counts.get(st, 0) + 1
    summary = ", ".join(f"{n} {st}" for st, n in counts.items())
    return f"<p>{len(holes)} holes: {_esc(summary)}.</p>\n" + "\n".join(out)


def _history_summary(history: Sequence[Mapping]) -> str:
    """Table with the first and last recorded values of each history key."""
    rows = []
    for key in _HISTORY_KEYS:
        vals = [h.get(key) for h in history if isinstance(h, Mapping) and h.get(key) is not None]
        if not vals:
            continue
        if key == "stage":
            seen: list = []
            for v in vals:
                if not seen or seen[-1] != v:
                    seen.append(v)
            rows.append(("stages", " → ".join(str(s) for s in seen)))
            continue
        first, last = vals[0], vals[-1]
        if _is_number(last) and not math.isfinite(float(last)):
            last = str(last)
        rows.append((f"{key} (first → last)", f"{_fmt(first)} → {_fmt(last)}"))
    return _table(rows, ("history", "value")) if rows else ""
