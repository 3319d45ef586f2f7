"""Every command keeps what it does not change (issue 27, parts 1 and 2).

Three real-format files are built from spot.ply with one hole cut in it: a coloured binary
float32 PLY (RGBA uchar, normals, a comment), a textured OBJ with two materials and its .mtl
and image beside it (per-corner ``vt`` indices that differ from the vertex indices), and an
ASCII double PLY with custom per-vertex (float, int) and per-face (int, float) properties.
Each goes through ``denoise``, ``fill``, ``inpaint``, ``complete`` (CLI) and the batch job
(``run_job``): the original vertices' values must come back bit-identical, the file's format
and precision kept, new vertices get values within the border's range, new faces their
neighbours' material and properties.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import plyfile
import pytest

from meshrepair.batch.jobs import run_job
from meshrepair.cli import main
from meshrepair.io import MeshData, carry_attributes, read_mesh, write_mesh

from .test_fill import compact, cut_disc

SPOT = Path(__file__).parent / "data" / "spot.ply"
SPHERE_R = 0.08


@pytest.fixture(scope="module")
def base():
    m = read_mesh(SPOT)
    Vc, Fc, removed, _ = cut_disc(m.V, m.F, 100, 3.0)
    VP, FP = compact(m.V, removed)
    Vc = Vc.astype(np.float32).astype(np.float64)  # exactly representable in every file
    return Vc, Fc, VP.astype(np.float32).astype(np.float64), FP


def colour_field(V: np.ndarray) -> np.ndarray:
    """A smooth RGB field in [0, 1] of the position."""
    return np.stack([0.5 + 0.4 * np.sin(3 * V[:, 0] + 1), 0.5 + 0.4 * np.cos(2 * V[:, 1]),
                     0.5 + 0.4 * np.sin(V[:, 2] * 2 + V[:, 0])], axis=1)


def uv_field(V: np.ndarray) -> np.ndarray:
    return np.stack([0.5 + 0.3 * V[:, 0] + 0.1 * V[:, 2], 0.5 + 0.3 * V[:, 1]], axis=1)


def _write_ply(path: Path, vert: np.ndarray, face: np.ndarray, text: bool,
               comments=()) -> None:
    el = [plyfile.PlyElement.describe(vert, "vertex"), plyfile.PlyElement.describe(face, "face")]
    plyfile.PlyData(el, text=text, comments=list(comments)).write(str(path))


def make_coloured(path: Path, V, F) -> None:
    from meshrepair.mesh.geometry import vertex_normals

    N = vertex_normals(V, F)
    C = np.rint(colour_field(V) * 255).astype(np.uint8)
    vert = np.empty(len(V), dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("nx", "f4"),
                                   ("ny", "f4"), ("nz", "f4"), ("red", "u1"), ("green", "u1"),
                                   ("blue", "u1"), ("alpha", "u1")])
    for k, n in enumerate("xyz"):
        vert[n] = V[:, k]
        vert["n" + n] = N[:, k]
    for k, n in enumerate(("red", "green", "blue")):
        vert[n] = C[:, k]
    vert["alpha"] = 200
    face = np.empty(len(F), dtype=[("vertex_indices", "i4", (3,))])
    face["vertex_indices"] = F
    _write_ply(path, vert, face, text=False, comments=["scanner: structured light, unit mm"])


def make_custom(path: Path, V, F) -> None:
    vert = np.empty(len(V), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8"), ("quality", "f4"),
                                   ("segment", "i4")])
    for k, n in enumerate("xyz"):
        vert[n] = V[:, k]
    vert["quality"] = (V[:, 0] + 2 * V[:, 1]).astype(np.float32)
    vert["segment"] = (V[:, 2] > 0).astype(np.int32) + 3
    face = np.empty(len(F), dtype=[("vertex_indices", "i4", (3,)), ("part", "i4"),
                                   ("weight", "f4")])
    face["vertex_indices"] = F
    face["part"] = (V[F].mean(axis=1)[:, 1] > 0).astype(np.int32) + 10
    face["weight"] = np.linspace(0, 1, len(F)).astype(np.float32)
    _write_ply(path, vert, face, text=True)


def make_textured(folder: Path, V, F, seam_x: float | None = None) -> Path:
    """OBJ + .mtl + image; ``vt`` rows in a shuffled order (per-corner indices differ from the
    vertex indices); materials by the side of the face (x > 0); with ``seam_x``, the faces with
    x > seam_x use a second copy of the texture coordinates shifted by 0.5 in u (a texture
    seam along x = seam_x)."""
    uv = uv_field(V)
    perm = np.random.default_rng(0).permutation(len(V))
    table = np.empty_like(uv)
    table[perm] = uv
    right = V[F].mean(axis=1)[:, 0] > 0
    TC = perm[F]
    if seam_x is not None:
        table = np.vstack([table, table + [0.5, 0.0]])
        TC = np.where((V[F].mean(axis=1)[:, 0] > seam_x)[:, None], TC + len(V), TC)
    (folder / "texture.png").write_bytes(b"\x89PNG\r\n\x1a\n not a real image")
    (folder / "scan.mtl").write_text("newmtl skin\nmap_Kd texture.png\nnewmtl eye\nKd 0 0 0\n")
    lines = ["# photogrammetry export", "mtllib scan.mtl"]
    lines += [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in V]
    lines += [f"vt {u:.17g} {t:.17g}" for u, t in table]
    cur = None
    for f, t, r in zip(F + 1, TC + 1, right, strict=True):
        mat = "eye" if r else "skin"
        if mat != cur:
            lines.append(f"usemtl {mat}")
            cur = mat
        lines.append("f " + " ".join(f"{a}/{b}" for a, b in zip(f, t, strict=True)))
    path = folder / "scan.obj"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def files(tmp_path_factory, base):
    V, F, VP, FP = base
    d = tmp_path_factory.mktemp("attrs")
    make_coloured(d / "coloured.ply", V, F)
    make_custom(d / "custom.ply", V, F)
    make_textured(d, V, F)
    tmpl = MeshData(V=VP, F=FP, vertex_attributes={
        "red": np.full(len(VP), 10, np.uint8), "green": np.full(len(VP), 20, np.uint8),
        "blue": np.full(len(VP), 250, np.uint8), "alpha": np.full(len(VP), 255, np.uint8)})
    write_mesh(d / "template.ply", VP, FP, like=tmpl)
    return d


def _centre(V):
    return V[1500]


def _cli(cmd: str, inp: Path, out: Path, d: Path, V) -> None:
    c = _centre(V)
    extra = {"denoise": [], "fill": [],
             "inpaint": ["--sphere=" + ",".join(repr(float(x)) for x in (*c, SPHERE_R))],
             "complete": ["--hole", "0", "--iterations", "5"]}[cmd]
    args = [cmd, str(inp)] + ([str(d / "template.ply")] if cmd == "complete" else [])
    assert main(args + [str(out), "-q", *extra]) == 0


def _job(cmd: str, inp: Path, out: Path, d: Path, V) -> None:
    c = _centre(V)
    opts = {"denoise": {}, "fill": {},
            "inpaint": {"region": ["sphere", c.tolist(), SPHERE_R]},
            "complete": {"template": str(d / "template.ply"), "hole": 0, "iterations": 5}}[cmd]
    rec = run_job(cmd, str(inp), str(out), opts)
    assert rec["status"] == "done", rec["error"]


def _vertex_map(cmd: str, m: MeshData, d: Path) -> np.ndarray:
    """Output index of every input vertex, from the library call the command makes."""
    import meshrepair as mr

    if cmd in ("denoise", "fill"):
        return np.arange(len(m.V))
    if cmd == "inpaint":
        return mr.inpaint(m.V, m.F, ("sphere", _centre(m.V), SPHERE_R)).vertex_map
    t = read_mesh(d / "template.ply")
    return mr.complete(m.V, m.F, template=(t.V, t.F), hole=0, iterations=5).vertex_map


def _header(path: Path) -> str:
    data = path.read_bytes()
    return data[:data.find(b"end_header")].decode()


COMMANDS = ["denoise", "fill", "inpaint", "complete"]


@pytest.mark.parametrize("runner", ["cli", "batch"])
@pytest.mark.parametrize("cmd", COMMANDS)
def test_coloured_float32_ply(files, base, tmp_path, cmd, runner):
    inp = files / "coloured.ply"
    out = tmp_path / "out.ply"
    (_cli if runner == "cli" else _job)(cmd, inp, out, files, base[0])
    m, r = read_mesh(inp), read_mesh(out)
    head = _header(out)
    assert "format binary_little_endian" in head and "property float x" in head
    assert "comment scanner: structured light, unit mm" in head
    vmap = _vertex_map(cmd, m, files)
    kept = vmap >= 0
    for n in ("red", "green", "blue", "alpha"):
        assert r.vertex_attributes[n].dtype == np.uint8
        assert np.array_equal(r.vertex_attributes[n][vmap[kept]], m.vertex_attributes[n][kept])
    new = np.setdiff1d(np.arange(len(r.V)), vmap[kept])
    assert (len(new) > 0) == (cmd != "denoise")
    tmpl = r.vertex_attributes["template"][new] == 1 if cmd == "complete" else False
    if cmd != "denoise":
        for n in ("red", "green", "blue"):  # harmonic: within the range of the values around
            v = r.vertex_attributes[n].astype(int)[new[~tmpl]]
            lo, hi = int(m.vertex_attributes[n].min()), int(m.vertex_attributes[n].max())
            assert ((lo <= v) & (v <= hi)).all()
    if cmd == "complete":  # the template's own colour on its interior vertices
        tv = new[tmpl]
        assert len(tv) > 0 and (r.vertex_attributes["blue"][tv] == 250).all()
    else:
        assert (r.vertex_attributes["alpha"] == 200).all()
    from meshrepair.mesh.geometry import vertex_normals

    N = np.stack([r.vertex_attributes[n] for n in ("nx", "ny", "nz")], axis=1)
    assert N.dtype == np.float32
    assert np.abs(N - vertex_normals(r.V, r.F)).max() < 1e-4  # recomputed for the output
    if cmd == "fill":  # unmoved float32 coordinates come back exactly
        assert np.array_equal(r.V[:len(m.V)], m.V)


@pytest.mark.parametrize("runner", ["cli", "batch"])
@pytest.mark.parametrize("cmd", COMMANDS)
def test_ascii_ply_custom_properties(files, base, tmp_path, cmd, runner):
    inp = files / "custom.ply"
    out = tmp_path / "out.ply"
    (_cli if runner == "cli" else _job)(cmd, inp, out, files, base[0])
    m, r = read_mesh(inp), read_mesh(out)
    head = _header(out)
    assert "format ascii" in head and "property double x" in head
    assert "property float quality" in head and "property int segment" in head
    assert "property int part" in head and "property float weight" in head
    vmap = _vertex_map(cmd, m, files)
    kept = vmap >= 0
    for n in ("quality", "segment"):
        assert r.vertex_attributes[n].dtype == m.vertex_attributes[n].dtype
        assert np.array_equal(r.vertex_attributes[n][vmap[kept]], m.vertex_attributes[n][kept])
    assert set(np.unique(r.vertex_attributes["segment"])) <= {3, 4}  # labels: never averaged
    # faces: kept ones keep their values; new ones take a neighbour's
    inv = np.full(len(r.V), -1)
    inv[vmap[kept]] = np.flatnonzero(kept)
    key_in = {tuple(sorted(f)): k for k, f in enumerate(m.F)}
    matched = 0
    for k, f in enumerate(r.F):
        g = inv[f]
        j = key_in.get(tuple(sorted(g))) if (g >= 0).all() else None
        if j is not None:
            matched += 1
            assert r.face_attributes["part"][k] == m.face_attributes["part"][j]
            assert r.face_attributes["weight"][k] == m.face_attributes["weight"][j]
        else:
            assert r.face_attributes["part"][k] in (10, 11)
    assert matched >= len(m.F) - 200


@pytest.mark.parametrize("runner", ["cli", "batch"])
@pytest.mark.parametrize("cmd", COMMANDS)
def test_textured_obj_with_materials(files, base, tmp_path, cmd, runner):
    inp = files / "scan.obj"
    mtl, png = (files / "scan.mtl").read_bytes(), (files / "texture.png").read_bytes()
    out = tmp_path / "out.obj"
    (_cli if runner == "cli" else _job)(cmd, inp, out, files, base[0])
    m, r = read_mesh(inp), read_mesh(out)
    text = out.read_text()
    assert "mtllib scan.mtl" in text and "usemtl skin" in text and "usemtl eye" in text
    assert (files / "scan.mtl").read_bytes() == mtl and (files / "texture.png").read_bytes() == png
    assert r.material_libraries == ["scan.mtl"] and set(r.materials) == {"skin", "eye"}
    assert (r.face_materials >= 0).all()
    # the texture coordinate table is kept row for row, new rows after it
    assert np.array_equal(r.texcoords[:len(m.texcoords)], m.texcoords)
    vmap = _vertex_map(cmd, m, files)
    kept = vmap >= 0
    # every corner at an original vertex has that vertex's texture coordinate, bit for bit
    uv_in = np.empty((len(m.V), 2))
    uv_in[m.F.ravel()] = m.texcoords[m.face_texcoords.ravel()]
    inv = np.full(len(r.V), -1)
    inv[vmap[kept]] = np.flatnonzero(kept)
    corner_uv = r.texcoords[r.face_texcoords.ravel()]
    at_orig = inv[r.F.ravel()] >= 0
    assert np.array_equal(corner_uv[at_orig], uv_in[inv[r.F.ravel()][at_orig]])
    if cmd != "denoise":  # new vertices: interpolated within the border's range
        new = ~at_orig
        assert new.any()
        lo, hi = uv_in.min(axis=0), uv_in.max(axis=0)
        assert (corner_uv[new] >= lo - 1e-12).all() and (corner_uv[new] <= hi + 1e-12).all()
    # the material of each kept face
    key_in = {tuple(sorted(f)): k for k, f in enumerate(m.F)}
    for k, f in enumerate(r.F):
        g = inv[f]
        j = key_in.get(tuple(sorted(g))) if (g >= 0).all() else None
        if j is not None:
            assert r.materials[r.face_materials[k]] == m.materials[m.face_materials[j]]


def test_seam_across_a_hole_is_named(tmp_path, base, caplog):
    import meshrepair as mr
    from meshrepair.mesh.topology import boundary_loops

    V, F, _, _ = base
    loop = boundary_loops(F, len(V))[0]
    m0 = read_mesh(make_textured(tmp_path, V, F))
    res = mr.fill_holes(m0.V, m0.F)
    with caplog.at_level(logging.WARNING, logger="meshrepair"):
        carry_attributes(m0, res)
    assert "texture seam" not in caplog.text  # no seam: nothing to say
    m = read_mesh(make_textured(tmp_path, V, F, seam_x=float(V[loop, 0].mean())))
    with caplog.at_level(logging.WARNING, logger="meshrepair"):
        out = carry_attributes(m, res)
    msg = [r.getMessage() for r in caplog.records if "texture seam" in r.getMessage()]
    assert len(msg) == 1 and "border vertices" in msg[0]
    assert len(out.texcoords) == len(m.texcoords) + len(res.new_vertices)


def test_formats_that_cannot_hold_it_warn(files, tmp_path, capsys, caplog):
    out = tmp_path / "out.stl"
    with caplog.at_level(logging.WARNING, logger="meshrepair"):
        assert main(["fill", str(files / "coloured.ply"), str(out), "-q"]) == 0
    msgs = [r.getMessage() for r in caplog.records if "not stored" in r.getMessage()]
    assert len(msgs) == 1 and "red" in msgs[0] and ".stl" in msgs[0]
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="meshrepair"):
        assert main(["fill", str(files / "scan.obj"), str(tmp_path / "o.off"), "-q"]) == 0
    assert "texture coordinates" in caplog.text and "materials" in caplog.text


def test_api_trimesh_visuals_in_and_out(base):
    import trimesh

    import meshrepair as mr

    V, F, _, _ = base
    C = np.c_[np.rint(colour_field(V) * 255), np.full(len(V), 255)].astype(np.uint8)
    tm = trimesh.Trimesh(V, F, vertex_colors=C, process=False)
    res = mr.fill_holes(tm)
    out = carry_attributes(tm, res)
    assert isinstance(out, trimesh.Trimesh) and out.visual.kind == "vertex"
    assert np.array_equal(out.visual.vertex_colors[:len(V)], C)
    assert len(out.vertices) == len(res.V)
    tex = trimesh.Trimesh(V, F, visual=trimesh.visual.TextureVisuals(uv=uv_field(V)),
                          process=False)
    out = carry_attributes(tex, mr.fill_holes(tex))
    assert out.visual.kind == "texture"
    assert np.array_equal(out.visual.uv[:len(V)], uv_field(V))


def test_api_read_task_write(files, tmp_path):
    import meshrepair as mr

    m = read_mesh(files / "coloured.ply")
    res = mr.fill_holes(m.V, m.F)
    out = carry_attributes(m, res)
    write_mesh(tmp_path / "o.ply", out.V, out.F, like=out)
    r = read_mesh(tmp_path / "o.ply")
    assert r.file_format.precision == "float32" and r.file_format.binary
    assert np.array_equal(r.vertex_attributes["red"][:len(m.V)], m.vertex_attributes["red"])
    with pytest.raises(mr.MeshRepairError, match="carry_attributes"):
        write_mesh(tmp_path / "bad.ply", res.V, res.F, like=m)


def test_batch_command_on_dask_writes_what_the_single_command_writes(files, tmp_path):
    """``meshrepair batch`` (a real LocalCluster) over the three files: each output is
    byte-identical to the single ``fill`` command's, whose content the tests above check."""
    import shutil

    src = tmp_path / "in"
    src.mkdir()
    for name in ("coloured.ply", "custom.ply", "scan.obj", "scan.mtl", "texture.png"):
        shutil.copy(files / name, src / name)
    out = tmp_path / "out"
    assert main(["batch", str(src), str(out), "--task", "fill", "--workers", "1", "-q"]) == 0
    for name in ("coloured.ply", "custom.ply", "scan.obj"):
        ref = tmp_path / f"ref_{name}"
        assert main(["fill", str(src / name), str(ref), "-q"]) == 0
        assert (out / name).read_bytes() == ref.read_bytes(), name


def test_cli_names_a_seam_once(tmp_path, base, capsys):
    """The CLI prints the texture-seam warning once (logging's handler on stderr), naming the
    border vertices, and still writes the file."""
    from meshrepair.mesh.topology import boundary_loops

    V, F, _, _ = base
    loop = boundary_loops(F, len(V))[0]
    inp = make_textured(tmp_path, V, F, seam_x=float(V[loop, 0].mean()))
    out = tmp_path / "out.obj"
    root = logging.getLogger()
    handler = logging.StreamHandler()
    root.addHandler(handler)
    try:
        assert main(["fill", str(inp), str(out), "-q"]) == 0
    finally:
        root.removeHandler(handler)
    err = capsys.readouterr().err
    assert err.count("texture seam crosses a repaired patch") == 1
    assert read_mesh(out).face_texcoords is not None
