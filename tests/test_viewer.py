"""Tests of meshrepair.viewer (page content, packing, decimation), meshrepair.render.framing and the
``view`` command, without a browser (the browser tests are in test_viewer_browser.py)."""

from __future__ import annotations

import base64
import json
import os
from importlib import resources

import numpy as np
import pytest
import trimesh

from meshrepair.errors import MeshRepairError
from meshrepair.render.framing import frame_faces, frame_hole, frame_loop, view_axes
from meshrepair.viewer import ViewerMesh, cluster_decimate, viewer_section, write_viewer
from meshrepair.viewer.content import hole_outcome, mesh_pane, mesh_regions


def holey_sphere(sub: int = 3):
    s = trimesh.creation.icosphere(subdivisions=sub)
    V, F = np.asarray(s.vertices), np.asarray(s.faces, dtype=np.int64)
    c = V[F].mean(axis=1)
    F = F[(c[:, 0] < 0.8) & (c[:, 1] < 0.93)]
    used = np.unique(F)
    remap = -np.ones(len(V), np.int64)
    remap[used] = np.arange(len(used))
    return V[used], remap[F]


def page_data(section: str) -> dict:
    raw = section.split('<script type="application/json" id="mr-viewer-data">')[1]
    return json.loads(raw.split("</script>")[0])


def decode(s: str, dtype: str) -> np.ndarray:
    return np.frombuffer(base64.b64decode(s), dtype=dtype)


# ------------------------------------------------------------------------------------------
# the vendored three.js


def test_three_is_vendored_pinned_with_its_licence():
    vendor = resources.files("meshrepair.viewer").joinpath("vendor")
    version = vendor.joinpath("THREE_VERSION").read_text().strip()
    assert version == "0.187.0"
    bundle = vendor.joinpath("three.bundle.min.js").read_text(encoding="utf-8")
    assert bundle.startswith(f"/* three.js {version} (npm package 'three'), MIT licence")
    assert "export{" in bundle.replace(" ", "") and "OrbitControls" in bundle  # an ES module
    assert "</script" not in bundle.lower()
    lic = vendor.joinpath("LICENSE-three.txt").read_text(encoding="utf-8")
    assert "The MIT License" in lic and "three.js authors" in lic
    assert vendor.joinpath("build.sh").read_text().count("three@${THREE_VERSION}") == 1


# ------------------------------------------------------------------------------------------
# page content


def test_section_embeds_meshes_as_binary_and_three_as_a_data_module():
    V, F = holey_sphere()
    sec = viewer_section([ViewerMesh("a </script><b>x</b>", V, F, scalars={"h": V[:, 1]}),
                          ViewerMesh("b", V + 1.0, F)])
    data = page_data(sec)
    p0 = data["panes"][0]
    assert p0["title"] == "a </script><b>x</b>"  # carried as JSON text, escaped for the page
    assert sec.count("</script>") == 3 and "<b>x</b>" not in sec
    assert np.array_equal(decode(p0["positions"], "<f4").reshape(-1, 3), V.astype(np.float32))
    assert np.array_equal(decode(p0["indices"], "<u4").reshape(-1, 3), F)
    assert np.allclose(decode(p0["scalars"]["h"], "<f4"), V[:, 1], atol=1e-6)
    assert "h" not in data["panes"][1]["scalars"] and not p0["decimated"]
    lo, hi = data["scalars"]["h"]["lo"], data["scalars"]["h"]["hi"]
    assert -1 < lo < hi < 1
    imports = json.loads(sec.split('<script type="importmap">')[1].split("</script>")[0])
    url = imports["imports"]["three"]
    assert url.startswith("data:text/javascript;base64,")
    bundle = resources.files("meshrepair.viewer").joinpath("vendor/three.bundle.min.js")
    assert base64.b64decode(url.split(",", 1)[1]) == bundle.read_bytes()
    assert "http://" not in sec and "https://" not in sec
    # scene sphere holds both meshes
    c, r = np.array(data["scene"]["center"]), data["scene"]["radius"]
    assert np.all(np.linalg.norm(np.r_[V, V + 1.0] - c, axis=1) <= r + 1e-9)


def test_masks_are_categorical_and_decimation_keeps_them():
    V, F = holey_sphere(4)
    mask = (V[:, 2] > 0.5).astype(np.uint8)
    sec = viewer_section([ViewerMesh("m", V, F, scalars={"filled": mask})], face_budget=800)
    data = page_data(sec)
    spec = data["scalars"]["filled"]
    assert spec["categories"] == [0.0, 1.0] and len(spec["colors"]) == 2
    p = data["panes"][0]
    assert p["decimated"] and p["shownF"] <= 800 and p["nF"] == len(F)
    vals = decode(p["scalars"]["filled"], "<f4")
    assert set(np.unique(vals)) <= {0.0, 1.0} and vals.max() == 1.0


def test_cluster_decimate_budget_validity_and_values():
    s = trimesh.creation.icosphere(subdivisions=5)
    V, F = np.asarray(s.vertices), np.asarray(s.faces)
    same = cluster_decimate(V, F, len(F))
    assert not same.decimated and same.F is not None and len(same.F) == len(F)
    d = cluster_decimate(V, F, 2000)
    assert d.decimated and 200 < len(d.F) <= 2000
    assert d.F.min() >= 0 and d.F.max() < len(d.V)
    assert np.all((d.F[:, 0] != d.F[:, 1]) & (d.F[:, 1] != d.F[:, 2]) & (d.F[:, 0] != d.F[:, 2]))
    assert len(np.unique(np.sort(d.F, axis=1), axis=0)) == len(d.F)
    r = np.linalg.norm(d.V, axis=1)  # cluster means of unit-sphere points stay near it
    assert r.max() <= 1 + 1e-9 and r.min() > 0.9
    z = d.vertex_values(V[:, 2])
    assert np.nanmax(np.abs(z - d.V[:, 2])) < 1e-9  # the mean of z is the mean position's z
    with pytest.raises(MeshRepairError, match="at least 100"):
        cluster_decimate(V, F, 10)


def test_write_viewer_is_atomic_with_usual_permissions(tmp_path):
    V, F = holey_sphere(1)
    out = write_viewer(tmp_path / "v.html", [ViewerMesh("x", V, F)],
                       metrics={"faces": [len(F)]}, title="T <i>")
    text = out.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>") and "<title>T &lt;i&gt;</title>" in text
    assert [p.name for p in tmp_path.iterdir()] == ["v.html"]  # no temporary file left
    umask = os.umask(0)
    os.umask(umask)
    assert out.stat().st_mode & 0o777 == 0o666 & ~umask
    with pytest.raises(MeshRepairError, match="1 to 8"):
        viewer_section([])
    with pytest.raises(MeshRepairError, match="one value per mesh"):
        write_viewer(tmp_path / "w.html", [ViewerMesh("x", V, F)], metrics={"a": [1, 2]})


def test_mesh_pane_and_regions():
    V, F = holey_sphere()
    filled = np.zeros(len(V), np.uint8)
    filled[V[:, 2] > 0.9] = 1
    pane = mesh_pane(V, F, "p", attributes={"filled": filled, "junk": np.zeros(3)})
    assert set(pane.scalars) == {"mean curvature", "filled"}
    assert pane.highlight is not None and pane.highlight_label == "filled faces"
    assert np.array_equal(pane.highlight, filled[F].any(axis=1).astype(bool))
    frames, details = mesh_regions(V, F, highlight=pane.highlight, label="filled")
    names = [f.name for f in frames]
    assert names == ["hole 0", "hole 1", "filled 0"]
    assert details[0].startswith("open: ")
    assert frames[2].normal @ np.array([0, 0, 1.0]) > 0.95
    assert hole_outcome({"status": "skipped", "reason": "longer than 10"}) == \
        "skipped: longer than 10"
    assert hole_outcome({"status": "filled", "reason": "plane", "n_new_vertices": 3,
                         "n_new_faces": 7}) == "filled (plane; 3 vertices, 7 faces)"


# ------------------------------------------------------------------------------------------
# framing


def test_frame_hole_faces_the_hole_from_outside():
    V, F = holey_sphere()
    big, small = frame_hole(V, F, 0), frame_hole(V, F, 1)
    assert big.normal @ np.array([1.0, 0, 0]) > 0.99  # the cap around +x, seen from outside
    assert small.normal @ np.array([0, 1.0, 0]) > 0.99
    assert big.radius > small.radius > 0
    assert np.linalg.norm(big.center - [0.82, 0, 0]) < 0.1
    # reversing the loop gives the same outward normal (oriented by the faces around it)
    from meshrepair.holes import find_holes

    h = find_holes(V, F)[0]
    assert np.allclose(frame_loop(V, F, h.vertices[::-1]).normal, big.normal)
    with pytest.raises(MeshRepairError, match="has 2 holes"):
        frame_hole(V, F, 2)
    fr = frame_faces(V, F, np.flatnonzero(V[F].mean(axis=1)[:, 2] > 0.9))
    assert fr.normal @ np.array([0, 0, 1.0]) > 0.99
    with pytest.raises(MeshRepairError, match="empty"):
        frame_faces(V, F, np.zeros(len(F), bool))


def test_view_axes_are_a_right_handed_camera():
    from meshrepair.render import _camera_axes

    assert np.allclose(view_axes([0, 0, -1]), _camera_axes(0, 0))
    assert np.allclose(view_axes([-1, 0, 0]), _camera_axes(90, 0))
    assert np.allclose(view_axes([0, -1, 0]), _camera_axes(0, 90), atol=1e-12)
    A = view_axes([0.3, -0.2, 0.9])
    assert np.allclose(A @ A.T, np.eye(3)) and np.isclose(np.linalg.det(A), 1.0)
    with pytest.raises(MeshRepairError, match="view direction"):
        view_axes([0, 0, 0])


# ------------------------------------------------------------------------------------------
# the view command


def test_cli_view(tmp_path, capsys):
    from meshrepair.cli import main

    V, F = holey_sphere()
    a = tmp_path / "a.ply"
    trimesh.Trimesh(V, F, process=False).export(a)
    out = tmp_path / "v.html"
    assert main(["view", str(a), str(a), "-o", str(out), "--titles", "one", "two"]) == 0
    assert "2 panes, 4 holes/regions" in capsys.readouterr().out
    data = page_data(out.read_text(encoding="utf-8"))
    assert [p["title"] for p in data["panes"]] == ["one", "two"]
    assert [r["name"] for r in data["regions"]][:2] == ["one: hole 0", "one: hole 1"]
    assert "sharp" in data["panes"][0]
    assert main(["view", str(a), "-o", str(out)]) == 2  # exists: needs --force
    assert "--force" in capsys.readouterr().err
    assert main(["view", str(a), "-o", str(out), "--force", "--face-budget", "500"]) == 0
    assert page_data(out.read_text(encoding="utf-8"))["panes"][0]["decimated"]
    assert main(["view", str(a), "-o", str(a)]) == 2  # never the input
    assert main(["view", str(a), "-o", str(tmp_path / "v.png")]) == 2
    assert main(["view", str(a), "-o", str(tmp_path / "x.html"), "--titles", "1", "2"]) == 2


def test_complete_and_inpaint_reports_highlight_their_faces(tmp_path):
    from meshrepair.cli import main
    from meshrepair.complete.api import extract_patch
    from meshrepair.io import write_mesh

    s = trimesh.creation.icosphere(subdivisions=3)
    V, F = np.asarray(s.vertices, float), np.asarray(s.faces, np.int64)
    cap = np.flatnonzero((V[F][:, :, 2] > 0.7).all(axis=1))
    VP, FP = extract_patch(V, F, cap)
    inp = write_mesh(tmp_path / "in.ply", V, F)
    tpl = write_mesh(tmp_path / "tpl.ply", VP + [3.0, 0, 0], FP)
    reg = tmp_path / "region.txt"
    reg.write_text("\n".join(map(str, cap)))
    rep = tmp_path / "c.html"
    assert main(["complete", str(inp), str(tpl), str(tmp_path / "out.ply"), "--region",
                 str(reg), "--iterations", "5", "--report", str(rep)]) == 0
    out = page_data(rep.read_text(encoding="utf-8"))["panes"][1]
    assert out["highlightLabel"] == "template faces" and out["highlightCount"] > 0
    rep2 = tmp_path / "i.html"
    assert main(["inpaint", str(inp), str(tmp_path / "i.ply"), "--sphere", "0,0,1,0.3", "-q",
                 "--report", str(rep2)]) == 0
    data = page_data(rep2.read_text(encoding="utf-8"))
    assert data["panes"][1]["highlightLabel"] == "inpainted faces"
    assert [r["name"] for r in data["regions"]] == ["hole 0"]
    assert data["regions"][0]["detail"].startswith("filled (")
    assert np.dot(data["regions"][0]["normal"], [0, 0, 1]) > 0.95
