"""``OUT/index.html``: the report of a batch run, one row per mesh, failures first.

Each row shows the before/after thumbnails the workers rendered with
:func:`meshrepair.render.render_mesh` (kept as PNG files under ``OUT/thumbnails/`` and embedded in
the page as ``data:image/png;base64`` URIs, so the page shows them when copied or mailed alone),
the status or error message, the sizes, time, peak memory and the task's metrics. The page is one
static file without scripts; the output meshes are linked relatively. It is written atomically
(temporary file, then rename).
"""

from __future__ import annotations

import datetime
import html
import os
import urllib.parse
from pathlib import Path

from meshrepair.atomic import atomic_write
from meshrepair.batch.collection import INDEX, RECORDS


def _esc(x: object) -> str:
    return html.escape(str(x), quote=True)


def _fmt(v: object) -> str:
    if isinstance(v, bool) or v is None:
        return str(v)
    if isinstance(v, float):
        return f"{v:.4g}"
    if isinstance(v, list):
        return "; ".join(map(str, v)) if v else "-"
    return str(v)


def _rel_link(path: str | None, out: Path) -> str | None:
    """The URL of ``path`` from the page in ``out``: relative, with '#', '%', '?', ':' and
    spaces of file names percent-encoded ('/' kept); a file URI on another drive."""
    if not path:
        return None
    try:
        rel = Path(os.path.relpath(Path(path).resolve(), out.resolve())).as_posix()
    except ValueError:  # another drive (Windows)
        return Path(path).resolve().as_uri()
    return urllib.parse.quote(rel, safe="/")


def _thumb(path: str | None, alt: str) -> str:
    """The thumbnail's cell, its PNG embedded as a data URI (``-`` when there is none)."""
    import base64

    if not path:
        return '<td class="thumb">-</td>'
    try:
        png = Path(path).read_bytes()
    except OSError:
        return f'<td class="thumb">{_esc(alt)}: missing</td>'
    uri = "data:image/png;base64," + base64.b64encode(png).decode("ascii")
    return (f'<td class="thumb"><img src="{uri}" alt="{_esc(alt)}" width="160" '
            'height="160"></td>')


def _row(rec: dict, out: Path) -> str:
    ok = rec.get("status") == "done"
    status = "done" + (" (resumed)" if rec.get("resumed") else "") if ok else "failed"
    name = _esc(rec.get("rel", rec.get("input", "?")))
    link = _rel_link(rec.get("output"), out) if ok else None
    mesh = f'<a href="{_esc(link)}">{name}</a>' if link else name
    thumbs = rec.get("thumbnails") or {}
    sizes = "-"
    if rec.get("vertices") is not None:
        sizes = f"{rec['vertices']} V, {rec['faces']} F"
        if rec.get("out_vertices") is not None:
            sizes += f" &rarr; {rec['out_vertices']} V, {rec['out_faces']} F"
    metrics = "".join(f"<div>{_esc(k)}: {_esc(_fmt(v))}</div>"
                      for k, v in (rec.get("metrics") or {}).items())
    metrics += "".join(f'<div class="warn">warning: {_esc(w)}</div>'
                       for w in rec.get("warnings") or [])
    if not ok:
        metrics = f'<div class="err">{_esc(rec.get("error") or "unknown error")}</div>' + metrics
    secs = rec.get("seconds")
    mem = rec.get("peak_rss_mb")
    return (f'<tr class="{"ok" if ok else "bad"}"><td>{mesh}</td><td>{_esc(status)}</td>'
            f'{_thumb(thumbs.get("before"), "before")}'
            f'{_thumb(thumbs.get("after"), "after")}'
            f"<td>{sizes}</td><td>{'-' if secs is None else f'{secs:.2f}'}</td>"
            f"<td>{'-' if mem is None else f'{mem:.0f}'}</td><td>{metrics}</td></tr>")


_CSS = """body{font-family:sans-serif;margin:1.5em;color:#222}
table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:4px 8px;vertical-align:top;
font-size:13px}th{background:#eee}tr.bad{background:#fff0f0}.err{color:#a00;max-width:40em}
.warn{color:#850;max-width:40em}
td.thumb{padding:0}code{background:#f4f4f4;padding:0 3px}"""


def write_index(out_dir: str | os.PathLike, records: list[dict], *, task: str, options: dict,
                version: str) -> Path:
    """Write ``OUT/index.html`` for ``records`` (failures first, then by relative path)."""
    out = Path(out_dir)
    recs = sorted(records, key=lambda r: (r.get("status") == "done", str(r.get("rel", ""))))
    n_ok = sum(r.get("status") == "done" for r in records)
    n_res = sum(bool(r.get("resumed")) for r in records)
    total_s = sum(r.get("seconds") or 0.0 for r in records if not r.get("resumed"))
    when = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    opts = ", ".join(f"{k}={v!r}" for k, v in options.items()) or "defaults"
    rows = "\n".join(_row(r, out) for r in recs)
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>meshrepair batch {_esc(task)}</title>
<style>{_CSS}</style></head><body>
<h1>meshrepair batch: {_esc(task)}</h1>
<p>{len(records)} meshes: <b>{n_ok} repaired</b>{f" ({n_res} resumed)" if n_res else ""},
<b>{len(records) - n_ok} failed</b>; {total_s:.1f} s of worker time in this run.
meshrepair {_esc(version)}, {_esc(when)}. Options: <code>{_esc(opts)}</code>.
Records: <a href="{RECORDS}">{RECORDS}</a>.</p>
<table><thead><tr><th>mesh</th><th>status</th><th>before</th><th>after</th><th>size</th>
<th>time (s)</th><th>peak RSS (MB)</th><th>metrics / error</th></tr></thead>
<tbody>
{rows}
</tbody></table></body></html>
"""
    with atomic_write(out / INDEX, "w", make_parents=True) as fh:
        fh.write(page)
    return out / INDEX
