"""Tests of meshrepair.report (self-contained HTML report) and the ``report`` sub-command."""

from __future__ import annotations

import argparse
import base64
import io
import json
from html.parser import HTMLParser

import numpy as np
import pytest
import trimesh

from meshrepair.errors import MeshRepairError
from meshrepair.mesh.topology import edge_topology
from meshrepair.report.page import convergence_plot, write_report

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
DATA_PNG = "data:image/png;base64,"


def sphere(subdivisions: int = 2) -> tuple[np.ndarray, np.ndarray]:
    s = trimesh.creation.icosphere(subdivisions=subdivisions)
    return np.asarray(s.vertices), np.asarray(s.faces, dtype=np.int64)


class PageParser(HTMLParser):
    """Collects image sources, table count, cell texts and all text of an HTML page."""

    def __init__(self) -> None:
        super().__init__()
        self.images: list[str] = []
        self.tables = 0
        self.cells: list[str] = []
        self.text: list[str] = []
        self.tags: list[str] = []
        self.scripts: list[dict] = []
        self._in_cell = False

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        if tag == "script":
            self.scripts.append(dict(attrs))
        if tag == "img":
            self.images.append(dict(attrs).get("src", ""))
        elif tag == "table":
            self.tables += 1
        elif tag in ("td", "th"):
            self._in_cell = True
            self.cells.append("")

    def handle_endtag(self, tag):
        if tag in ("td", "th"):
            self._in_cell = False

    def handle_data(self, data):
        self.text.append(data)
        if self._in_cell:
            self.cells[-1] += data


def parse(path) -> PageParser:
    p = PageParser()
    p.feed(path.read_text(encoding="utf-8"))
    p.close()
    return p


def decode_png(src: str) -> np.ndarray:
    from matplotlib.image import imread

    assert src.startswith(DATA_PNG)
    raw = base64.b64decode(src[len(DATA_PNG):], validate=True)
    assert raw[:8] == PNG_MAGIC
    return imread(io.BytesIO(raw), format="png")


def history() -> list[dict]:
    h = []
    for k in range(12):
        h.append({"iter": k, "energy": 10.0 * 0.7**k + 1.0, "rel_change": 0.5**k,
                  "res_t": 0.3 * 0.6**k, "res_N": 0.2 * 0.65**k, "time": 0.01 * k,
                  "stage": "denoise" if k < 6 else "refine"})
    del h[3]["res_t"], h[4]["energy"]  # keys may be missing
    return h


def test_report_is_self_contained_with_tables_images_and_metrics(tmp_path):
    V, F = sphere(2)
    rng = np.random.default_rng(1)
    Vin = V + 0.01 * rng.standard_normal(V.shape)
    nE = edge_topology(F).n_edges
    out = tmp_path / "r" / "report.html"
    write_report(
        out,
        title="Sphere <denoising> & co",
        input_mesh=(Vin, F),
        output_mesh=(V, F),
        masks={"M_E": np.arange(nE) % 5 == 0, "M_V": V[:, 2] > 0.3},
        metrics={"MSAE": 1.23456789, "E_V": 0.000123456, "n_iter": 12},
        history=history(),
        parameters={"lambda": 0.5, "stages": ["denoise", "refine"], "note": "<b>not bold</b>"},
        timings={"solve": 1.5, "total": 2.25},
        image_size=160,
    )
    page = parse(out)
    raw = out.read_text(encoding="utf-8")
    # metric values, formatted with 6 significant digits, in table cells
    assert "1.23457" in page.cells and "0.000123456" in page.cells and "12" in page.cells
    assert page.tables >= 4  # meshes, metrics, parameters, timings (+ history summary)
    assert "2.25" in page.cells and "0.5" in page.cells
    # >= 2 embedded PNG images that decode: renders, 2 masks, convergence plot
    pngs = [s for s in page.images if s.startswith(DATA_PNG)]
    assert len(pngs) >= 4 and len(pngs) == len(page.images)
    shapes = [decode_png(s).shape for s in pngs]
    assert all(h > 50 and w > 50 for h, w, _ in shapes)
    # offline: only inline scripts (the viewer: import map of data: URLs, its data, its module),
    # no external resources, text escaped
    assert "link" not in page.tags
    assert [sc.get("type") for sc in page.scripts] == ["importmap", "application/json", "module"]
    assert all("src" not in sc for sc in page.scripts)
    imports = json.loads(raw.split('<script type="importmap">')[1].split("</script>")[0])
    assert list(imports["imports"]) == ["three"]
    assert imports["imports"]["three"].startswith("data:text/javascript;base64,")
    assert "http://" not in raw and "https://" not in raw
    assert "<denoising>" not in raw and "&lt;denoising&gt;" in raw
    assert "<b>" not in raw and "&lt;b&gt;not bold&lt;/b&gt;" in raw
    text = "".join(page.text)
    assert "M_E:" in text and "edges" in text and "M_V:" in text and "vertices" in text
    assert "vertexs" not in raw  # the plural of the mask captions
    assert f"of {len(V)} vertices on the output mesh" in text


def test_report_without_optional_parts(tmp_path):
    V, F = sphere(1)
    out = tmp_path / "min.html"
    write_report(out, title="minimal", output_mesh=(V, F), image_size=96, viewer=False)
    page = parse(out)
    text = "".join(page.text)
    assert "No convergence history recorded." in text and "No metrics given." in text
    assert len(page.images) == 1 and page.images[0].startswith(DATA_PNG)


def test_mask_of_unknown_length_is_rejected(tmp_path):
    V, F = sphere(1)
    with pytest.raises(MeshRepairError, match="matching no element count"):
        write_report(tmp_path / "x.html", title="t", output_mesh=(V, F),
                     masks={"M_V": np.ones(7, dtype=bool)}, image_size=96)
    with pytest.raises(MeshRepairError, match="output_mesh"):
        write_report(tmp_path / "x.html", title="t", output_mesh=V)


def test_convergence_plot_handles_gaps_restarts_and_empty():
    png = convergence_plot(history(), width=400, height=200)
    assert png[:8] == PNG_MAGIC
    # iteration counter restarting per stage, no energy at all, non-numeric junk
    h = [{"iter": k % 3, "rel_change": 10.0 ** -k, "stage": f"s{k // 3}", "res_N": "n/a"}
         for k in range(6)]
    assert convergence_plot(h, width=400, height=200)[:8] == PNG_MAGIC
    assert convergence_plot([]) is None
    assert convergence_plot([{"stage": "a"}, {"iter": 1}]) is None


def _parser() -> argparse.ArgumentParser:
    from meshrepair.commands import report as cmd

    parser = argparse.ArgumentParser(prog="meshrepair")
    sub = parser.add_subparsers(dest="command", required=True)
    cmd.register(sub)
    return parser


def test_cli_report(tmp_path):
    V, F = sphere(2)
    rng = np.random.default_rng(2)
    noisy = V + 0.02 * rng.standard_normal(V.shape)
    paths = {}
    for name, X in (("result", V + 0.001), ("input", noisy), ("truth", V)):
        paths[name] = tmp_path / f"{name}.ply"
        trimesh.Trimesh(X, F, process=False).export(paths[name])
    log = tmp_path / "run.json"
    log.write_text(json.dumps({"history": history(), "parameters": {"lambda": 0.25},
                               "timings": {"solve": 0.5}}))
    out = tmp_path / "report.html"
    args = _parser().parse_args(
        ["report", str(paths["result"]), str(out), "--input", str(paths["input"]),
         "--reference", str(paths["truth"]), "--log", str(log), "--image-size", "96"]
    )
    assert args.func(args) == 0
    page = parse(out)
    text = "".join(page.text)
    assert "MSAE vs reference (deg²)" in text and "E_V vs reference" in text
    assert "0.25" in page.cells
    assert len([s for s in page.images if s.startswith(DATA_PNG)]) >= 3
    # refuses to overwrite an input
    args = _parser().parse_args(["report", str(out), str(out)])
    with pytest.raises(MeshRepairError, match="overwrite"):
        args.func(args)


def test_hole_table_says_what_happened_to_each_hole(tmp_path):
    V, F = sphere(1)
    holes = [
        {"index": 0, "n_boundary": 40, "length": 2.5, "status": "filled", "reason": "plane",
         "n_new_vertices": 12, "n_new_faces": 30, "n_intersections": 0},
        {"index": 1, "n_boundary": 900, "length": 9.0, "status": "skipped",
         "reason": "longer than --max-hole-size 50", "n_new_vertices": 0, "n_new_faces": 0,
         "n_intersections": -1},
        {"index": 2, "n_boundary": 7, "length": 0.3, "status": "refused",
         "reason": "patch would intersect the mesh <x>"},
    ]
    out = tmp_path / "h.html"
    write_report(out, title="holes", output_mesh=(V, F), holes=holes, image_size=96,
                 viewer=False)
    page = parse(out)
    text = "".join(page.text)
    assert "3 holes: 1 filled, 1 skipped, 1 refused." in text
    for cell in ("plane", "longer than --max-hole-size 50", "refused", "not checked", "900"):
        assert cell in page.cells
    assert "patch would intersect the mesh <x>" in page.cells  # escaped in the file
    assert "<x>" not in out.read_text(encoding="utf-8")


def test_fill_report_has_hole_table_and_3d_view_of_the_holes(tmp_path):
    from meshrepair.cli import main

    V, F = sphere(3)
    c = V[F].mean(axis=1)
    F = F[(c[:, 0] < 0.8) & (c[:, 1] < 0.93)]
    src = tmp_path / "holey.ply"
    trimesh.Trimesh(V, F, process=False).export(src)
    rep = tmp_path / "fill.html"
    assert main(["fill", str(src), str(tmp_path / "out.ply"), "-q", "--max-hole-size", "20",
                 "--report", str(rep)]) == 0
    raw = rep.read_text(encoding="utf-8")
    page = parse(rep)
    assert "filled" in page.cells and "skipped" in page.cells
    data = json.loads(raw.split('id="mr-viewer-data">')[1].split("</script>")[0])
    assert [p["title"] for p in data["panes"]] == ["input", "output"]
    assert [r["name"] for r in data["regions"]] == ["hole 0", "hole 1"]
    details = [r["detail"] for r in data["regions"]]
    assert details[0].startswith("skipped: ") and details[1].startswith("filled (")
    assert data["panes"][1]["highlightLabel"] == "filled faces"
    assert data["panes"][1]["highlightCount"] > 0
