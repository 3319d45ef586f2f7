"""The one output rule of every command (commands/common.py) and the atomic writer (atomic.py):
never an input, never an existing file without --force, always atomic, a JSON log has a .json
name. Each test is one finding of issue 11."""

from __future__ import annotations

import os

import numpy as np
import pytest
import trimesh

from meshrepair.atomic import atomic_write, write_json
from meshrepair.cli import main
from meshrepair.errors import MeshRepairError
from meshrepair.io import read_mesh, write_mesh


def _sphere(path, subdiv=2):
    m = trimesh.creation.icosphere(subdiv)
    write_mesh(path, m.vertices, m.faces)
    return path


def _holed(path):
    m = trimesh.creation.icosphere(2)
    keep = m.vertices[m.faces].mean(axis=1)[:, 2] < 0.8
    write_mesh(path, m.vertices, m.faces[keep])
    return path


@pytest.fixture
def files(tmp_path):
    """A small mesh, a holed mesh and files that must survive every refused command."""
    d = {"in": _sphere(tmp_path / "in.ply"), "holed": _holed(tmp_path / "holed.ply")}
    d["json"] = tmp_path / "old.json"
    d["json"].write_text('{"keep": "me"}')
    d["html"] = tmp_path / "old.html"
    d["html"].write_text("<p>keep me</p>")
    d["png"] = tmp_path / "old.png"
    d["png"].write_bytes(b"\x89PNG keep me")
    return d


def _snapshot(folder):
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def _refused(capsys, argv, folder, match):
    """The command exits 2 with a message matching ``match`` and writes/changes no file."""
    before = _snapshot(folder)
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "error" in err and match in err, err
    assert _snapshot(folder) == before  # nothing written, nothing changed, no temp file left


@pytest.mark.parametrize("cmd", ["denoise", "fill"])
def test_log_naming_the_input_is_refused(tmp_path, files, capsys, cmd):
    src = files["holed" if cmd == "fill" else "in"]
    out = str(tmp_path / "out.ply")
    # --log IN.ply used to replace the input mesh with JSON
    _refused(capsys, [cmd, str(src), out, "-q", "--log", str(src)], tmp_path, ".json")
    _refused(capsys, [cmd, str(src), out, "-q", "--log", str(src), "--force"], tmp_path,
             ".json")
    # --log OUT.ply used to exit 0 with OUT no longer a mesh
    _refused(capsys, [cmd, str(src), out, "-q", "--log", out], tmp_path, ".json")
    assert read_mesh(src).n_faces > 0


@pytest.mark.parametrize("cmd", ["denoise", "fill", "complete"])
def test_existing_log_and_report_need_force(tmp_path, files, capsys, cmd):
    out = str(tmp_path / "out.ply")
    if cmd == "complete":
        reg = tmp_path / "reg.txt"
        reg.write_text("0 1 2")
        base = [cmd, str(files["in"]), str(files["holed"]), out, "--region", str(reg)]
    else:
        base = [cmd, str(files["holed" if cmd == "fill" else "in"]), out]
        base.append("-q")
    _refused(capsys, base + ["--log", str(files["json"])], tmp_path, "--force")
    _refused(capsys, base + ["--report", str(files["html"])], tmp_path, "--force")
    _refused(capsys, base + ["--report", str(tmp_path / "r.txt")], tmp_path, ".html")


def test_denoise_log_and_report_with_force_replace_atomically(tmp_path, files, capsys):
    out = tmp_path / "out.ply"
    assert main(["denoise", str(files["in"]), str(out), "-q", "--log", str(files["json"]),
                 "--report", str(files["html"]), "--force", "--feature-iters", "3",
                 "--robust-iters", "3"]) == 0
    assert "history" in files["json"].read_text() and "<html" in files["html"].read_text()
    assert read_mesh(out).n_vertices == read_mesh(files["in"]).n_vertices
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


def test_render_compare_report_refuse_existing_outputs(tmp_path, files, capsys):
    # render used to pass force=True
    _refused(capsys, ["render", str(files["in"]), str(files["png"])], tmp_path, "--force")
    _refused(capsys, ["compare", str(files["in"]), str(files["png"])], tmp_path, "--force")
    _refused(capsys, ["report", str(files["in"]), str(files["html"])], tmp_path, "--force")
    assert main(["render", str(files["in"]), str(files["png"]), "--size", "120", "100",
                 "--force"]) == 0
    assert files["png"].read_bytes()[:4] == b"\x89PNG" and len(files["png"].read_bytes()) > 100


def test_inpaint_region_mask_is_an_input(tmp_path, files, capsys):
    V = read_mesh(files["in"]).V
    mask = tmp_path / "mask.ply"
    write_mesh(mask, V, np.empty((0, 3), int),
               vertex_attributes={"region": (V[:, 2] > 0.9).astype(np.uint8)})
    # OUT = the region mask, even with --force: refused (only the main input was checked)
    _refused(capsys, ["inpaint", str(files["in"]), str(mask), "--region", str(mask), "--force",
                      "-q"], tmp_path, "input")


def test_complete_template_and_region_are_inputs(tmp_path, files, capsys):
    reg = tmp_path / "reg.npy"
    np.save(reg, np.zeros(3, bool))
    for out in (files["holed"], files["in"]):
        _refused(capsys, ["complete", str(files["in"]), str(files["holed"]), str(out),
                          "--region", str(reg), "--force"], tmp_path, "input")


def test_demo_second_run_refused_without_force(tmp_path, capsys):
    outdir = tmp_path / "demo"
    assert main(["demo", "--outdir", str(outdir), "--quiet", "--no-render"]) == 0
    first = (outdir / "fandisk_denoised.ply").read_bytes()
    (outdir / "fandisk_denoised.ply").write_bytes(b"user edited this")
    _refused(capsys, ["demo", "--outdir", str(outdir), "--quiet", "--no-render"], outdir,
             "--force")
    assert main(["demo", "--outdir", str(outdir), "--quiet", "--no-render", "--force"]) == 0
    assert (outdir / "fandisk_denoised.ply").read_bytes() == first
    f = tmp_path / "afile"
    f.write_text("x")
    _refused(capsys, ["demo", "--outdir", str(f), "--quiet"], tmp_path, "not a folder")


def test_output_hard_link_and_symlink_to_the_input_are_refused(tmp_path, files, capsys):
    link = tmp_path / "hard.ply"
    os.link(files["in"], link)
    sym = tmp_path / "sym.ply"
    sym.symlink_to(files["in"])
    for out in (link, sym):
        _refused(capsys, ["noise", str(files["in"]), str(out), "--force"], tmp_path, "input")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs POSIX FIFOs")
def test_non_regular_output_is_refused_even_with_force(tmp_path, files, capsys):
    fifo = tmp_path / "pipe.ply"
    os.mkfifo(fifo)
    before = _snapshot(tmp_path)
    assert main(["noise", str(files["in"]), str(fifo), "--force"]) == 2
    assert "not a regular file" in capsys.readouterr().err
    assert _snapshot(tmp_path) == before and fifo.exists() and not fifo.is_file()
    (tmp_path / "dir.ply").mkdir()
    assert main(["noise", str(files["in"]), str(tmp_path / "dir.ply"), "--force"]) == 2
    assert "directory" in capsys.readouterr().err


def test_dangling_symlink_output_is_refused_before_any_work(tmp_path, files, capsys):
    """An output name taken by a link to nothing is an existing name: refused at once without
    --force (the whole repair ran, then the final link step failed with 'it appeared while
    writing'); with --force the link itself is replaced by the file."""
    dang = tmp_path / "dang.ply"
    dang.symlink_to(tmp_path / "nothere.ply")
    _refused(capsys, ["noise", str(files["in"]), str(dang)], tmp_path, "dangling symbolic link")
    assert main(["noise", str(files["in"]), str(dang), "--force"]) == 0
    assert dang.is_file() and not dang.is_symlink() and not (tmp_path / "nothere.ply").exists()


def test_too_long_output_path_is_a_clear_error(tmp_path, files, capsys):
    out = tmp_path / ("x" * 300 + ".ply")
    assert main(["noise", str(files["in"]), str(out)]) == 2
    assert "too long" in capsys.readouterr().err.lower()


@pytest.mark.parametrize("argv", [["denoise", "{in}", ""], ["fill", "{holed}", ""],
                                  ["inpaint", "{in}", "", "--sphere", "0,0,1,0.3"],
                                  ["denoise", "{in}", "{out}", "--log", ""]])
def test_empty_output_name_is_refused_before_any_work(tmp_path, files, capsys, argv):
    argv = [a.format(**{"in": files["in"], "holed": files["holed"],
                        "out": tmp_path / "o.ply"}) for a in argv]
    _refused(capsys, argv, tmp_path, "empty name")


# ----------------------------------------------------------------------------------------------
# the atomic writer


def test_failed_write_keeps_the_old_file_and_leaves_no_temp(tmp_path):
    p = tmp_path / "a.json"
    p.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_write(p, "w") as fh:
            fh.write("half of the new")
            raise RuntimeError("disk on fire")
    assert p.read_text() == "old"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["a.json"]


def test_failed_mesh_write_keeps_the_old_file(tmp_path, monkeypatch):
    import meshrepair.io as mio

    p = _sphere(tmp_path / "m.ply")
    before = p.read_bytes()

    def broken(fh, *a, **k):
        fh.write(b"ply\nformat binary_little_endian 1.0\n")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(mio, "_write_ply", broken)
    with pytest.raises(MeshRepairError, match="No space left"):
        write_mesh(p, np.eye(3), np.array([[0, 1, 2]]))
    assert p.read_bytes() == before
    assert sorted(x.name for x in tmp_path.iterdir()) == ["m.ply"]


def test_overwrite_false_never_replaces(tmp_path):
    p = tmp_path / "a.json"
    p.write_text("old")
    with pytest.raises(MeshRepairError, match="exists"):
        write_json(p, {"a": 1}, overwrite=False)
    # a file appearing while writing is not replaced either
    q = tmp_path / "b.json"
    with pytest.raises(MeshRepairError, match="appeared while writing"):
        with atomic_write(q, "w", overwrite=False) as fh:
            fh.write("new")
            q.write_text("someone else's")
    assert p.read_text() == "old" and q.read_text() == "someone else's"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["a.json", "b.json"]


def test_json_log_needs_a_json_name(tmp_path):
    with pytest.raises(MeshRepairError, match=r"\.json"):
        write_json(tmp_path / "log.ply", {})
    p = write_json(tmp_path / "log.json", {"x": np.float32(1.5), "a": np.arange(3)})
    assert p.read_text().replace(" ", "").replace("\n", "") == '{"x":1.5,"a":[0,1,2]}'


def test_json_log_is_strict_json(tmp_path):
    """NaN and infinities, which strict parsers (jq, JavaScript) refuse, are written as null."""
    import json

    def refuse(c):
        raise ValueError(c)

    data = {"a": float("nan"), "b": [np.inf, 1.0], "c": {"d": np.float64(-np.inf)},
            "e": np.array([np.nan])}
    p = write_json(tmp_path / "log.json", data)
    assert json.loads(p.read_text(), parse_constant=refuse) == {"a": None, "b": [None, 1.0],
                                                                "c": {"d": None}, "e": [None]}


def test_output_folder_rule(tmp_path):
    from meshrepair.commands.common import make_folder, output_folder

    new = tmp_path / "new" / "deeper"
    paths = output_folder(new, ["a.ply", "b.png"], [])
    assert paths == [new / "a.ply", new / "b.png"] and not new.exists()  # nothing made yet
    assert make_folder(new).is_dir()
    (new / "b.png").write_bytes(b"old")
    with pytest.raises(MeshRepairError, match=r"b\.png' exists; pass --force"):
        output_folder(new, ["a.ply", "b.png"], [])
    assert output_folder(new, ["a.ply", "b.png"], [], force=True)[1].read_bytes() == b"old"
    src = new / "a.ply"
    src.write_bytes(b"input")
    with pytest.raises(MeshRepairError, match="input"):
        output_folder(new, ["a.ply"], [src], force=True)
