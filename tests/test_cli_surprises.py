"""What the CLI says matches what it did: progress counts, notes printed once per command."""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np
import pytest

import meshrepair as mr
from meshrepair.cli import main
from meshrepair.commands.common import ProgressBar
from meshrepair.io import read_mesh

from .bundled import data_path


def test_progress_bar_counts_the_pass_the_summary_reports(capsys):
    # the published noisy fandisk is solved twice by denoise (a check of the first result)
    m = read_mesh(data_path("fandisk_noisy.ply"))
    bar = ProgressBar(100, "denoise", enabled=True)
    seen = []

    def cb(entry):
        seen.append(entry)
        bar(entry)

    r = mr.denoise(m.V, m.F, callback=cb)
    assert bar.count == len(seen)
    assert bar.passes >= 2, "this input is expected to need a second solver pass"
    assert bar.bar.n == r.iterations  # the bar's last count is the summary's iterations
    assert str(len(seen)) in bar.passes_note() and str(bar.passes) in bar.passes_note()
    bar.close()


@pytest.mark.parametrize("name", ["fandisk_noisy.ply", "trim_star.ply"])
def test_progress_bar_lengths_come_from_the_plan(name):
    # the bar of the first pass is as long as the plan's stages, and no pass runs past its bar
    from meshrepair.commands.denoise import pass_lengths

    m = read_mesh(data_path(name))
    V = m.V if name.endswith("noisy.ply") else mr.add_noise(m.V, m.F, 0.3, seed=2)
    p = mr.plan_denoise(V, m.F)
    first, later = pass_lengths(p)
    assert first == sum(s.max_iter for s in (p.inner or p).stages) and later >= first
    bar = ProgressBar(first, "denoise", enabled=True, later=later)
    worst = []

    def cb(entry):
        bar(entry)
        worst.append(bar.bar.n <= bar.bar.total)

    r = mr.denoise(V, m.F, plan=p, callback=cb)
    bar.close()
    assert all(worst) and bar.bar.n == r.iterations
    np.testing.assert_array_equal(r.V, mr.denoise(V, m.F).V)  # the plan's run is the default


def test_progress_bar_one_pass_has_no_note():
    bar = ProgressBar(10, "x", enabled=False)
    for k in range(1, 6):
        bar({"iter": k, "rel_change": 0.1, "stage": "s"})
    assert bar.passes == 1 and bar.count == 5 and bar.passes_note() == ""


def test_denoise_summary_states_every_pass(tmp_path, capsys):
    out = tmp_path / "o.ply"
    assert main(["denoise", str(data_path("fandisk_noisy.ply")), str(out), "-q"]) == 0
    text = capsys.readouterr().out
    m = re.search(r"in (\d+) iterations .*the last of (\d+) solver passes, (\d+) iterations in "
                  r"all", text)
    assert m, text
    assert int(m.group(3)) > int(m.group(1))


def _pinched_mesh(path):
    """Two icospheres sharing one vertex (a pinched, non-manifold vertex)."""
    import numpy as np
    import trimesh

    from meshrepair.io import write_mesh

    a = trimesh.creation.icosphere(2)
    b = a.copy()
    b.apply_translation([2.0, 0.0, 0.0])
    i = int(np.argmax(a.vertices[:, 0]))
    j = int(np.argmin(b.vertices[:, 0])) + len(a.vertices)
    V = np.r_[a.vertices, b.vertices]
    F = np.r_[a.faces, b.faces + len(a.vertices)]
    F[F == j] = i
    keep = np.ones(len(V), bool)
    keep[j] = False
    remap = np.cumsum(keep) - 1
    return write_mesh(path, V[keep], remap[F])


@pytest.mark.parametrize("cmd", [["denoise", "{m}", "{o}.ply", "--report", "{o}.html"],
                                 ["fill", "{m}", "{o}.ply", "--report", "{o}.html"]])
def test_each_warning_once_per_command(tmp_path, cmd):
    m = _pinched_mesh(tmp_path / "pinched.ply")
    o = tmp_path / "out"
    argv = [a.format(m=m, o=o) for a in cmd]
    res = subprocess.run([sys.executable, "-m", "meshrepair.cli", *argv, "-q"],
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr[-2000:]
    lines = [x for x in res.stderr.splitlines() if x.startswith("WARNING")]
    pinched = [x for x in lines if "pinched" in x]
    assert len(pinched) == 1, res.stderr
    assert len(lines) == len(set(lines)), res.stderr


def _write_holed_sphere(path):
    import numpy as np
    import trimesh

    from meshrepair.io import write_mesh

    m = trimesh.creation.icosphere(3)
    V, F = np.asarray(m.vertices), np.asarray(m.faces)
    c = V[F].mean(axis=1)
    sub = trimesh.Trimesh(V, F[(c[:, 2] < 0.8) & (c[:, 0] < 0.8)], process=False)  # two holes
    sub.remove_unreferenced_vertices()
    return write_mesh(path, sub.vertices, sub.faces)


def _write_open_scan(path):
    """A height field over a square: an open surface whose only loop is its border."""
    import numpy as np
    from scipy.spatial import Delaunay

    from meshrepair.io import write_mesh

    xs = np.linspace(-1.0, 1.0, 20)
    X, Y = np.meshgrid(xs, xs)
    P = np.c_[X.ravel(), Y.ravel(), 0.2 * np.sin(2 * X.ravel()) * np.cos(Y.ravel())]
    return write_mesh(path, P, Delaunay(P[:, :2]).simplices)


@pytest.mark.parametrize(("make", "expect"), [(_write_holed_sphere, 2), (_write_open_scan, 0)])
def test_denoise_names_the_holes_it_keeps_and_points_to_fill(tmp_path, capsys, make, expect):
    src = make(tmp_path / "in.ply")
    out = tmp_path / "out.ply"
    assert main(["denoise", str(src), str(out), "-q"]) == 0
    text = capsys.readouterr().out
    if expect:
        assert f"note: the mesh has {expect} holes" in text
        assert f"meshrepair fill {out} FILLED.ply" in text
    else:
        assert "note:" not in text and "meshrepair fill" not in text


def test_first_run_says_it_compiles_and_the_summary_counts_it(tmp_path):
    import os

    src = _write_holed_sphere(tmp_path / "in.ply")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba-cache"))  # an empty cache
    env.pop("MESHREPAIR_NO_NUMBA", None)

    def run(out):
        res = subprocess.run([sys.executable, "-m", "meshrepair.cli", "denoise", str(src),
                              str(tmp_path / out)], capture_output=True, text=True, env=env,
                             timeout=600)
        assert res.returncode == 0, res.stderr[-2000:]
        return res

    cold = run("a.ply")
    assert cold.stderr.count("compiling kernels (first run only") == 1
    m = re.search(r"\(([\d.]+) s including ([\d.]+) s of one-off kernel compilation", cold.stdout)
    assert m, cold.stdout
    assert 0.5 <= float(m.group(2)) <= float(m.group(1))
    warm = run("b.ply")  # the same cache, now full
    assert "compiling kernels" not in warm.stderr
    assert "kernel compilation" not in warm.stdout


def test_reference_in_another_vertex_order_gives_no_per_vertex_errors(tmp_path, capsys):
    """The same surface stored with another vertex order (an STL, a re-export) compares by
    distances only: metrics, report, compare and view give no MSAE / E_V against it (they
    printed 12380 deg² for a mesh against itself); a reference of zero size gives no relative
    distances instead of a ZeroDivisionError."""
    from meshrepair.commands.render import reference_metrics

    m = read_mesh(data_path("fandisk.ply"))
    p = np.random.default_rng(0).permutation(len(m.V))
    inv = np.empty_like(p)
    inv[p] = np.arange(len(p))
    a, b = tmp_path / "a.ply", tmp_path / "b.ply"
    mr.write_mesh(a, m.V, m.F)
    mr.write_mesh(b, m.V[p], inv[m.F])
    assert reference_metrics(m.V, m.F, m.V[p], inv[m.F]) is None
    assert reference_metrics(m.V, m.F, m.V, m.F)["MSAE"] < 1e-9
    assert main(["metrics", str(a), str(b)]) == 0
    out = capsys.readouterr().out
    assert "MSAE (deg^2)" not in out and "need the same connectivity" in out
    assert re.search(r"mean distance\s+[0-9.e-]+", out)
    assert main(["report", str(a), str(tmp_path / "r.html"), "--reference", str(b)]) == 0
    page = (tmp_path / "r.html").read_text(encoding="utf-8")
    assert "MSAE vs reference" not in page and "mean surface distance" in page
    z = tmp_path / "zero.ply"
    mr.write_mesh(z, np.zeros_like(m.V), m.F)
    capsys.readouterr()
    assert main(["metrics", str(a), str(z)]) == 0
    assert "bbox diagonal" not in capsys.readouterr().out


def test_library_warnings_are_not_printed_without_logging_configured():
    """A program that does not configure logging sees no meshrepair warning on stderr (Python's
    last-resort handler printed them); the records still reach configured handlers."""
    code = ("import numpy as np, trimesh, meshrepair as mr\n"
            "s = trimesh.creation.icosphere(2)\n"
            "V = np.vstack([s.vertices, [[9.0, 9.0, 9.0]]])\n"  # an unused vertex: a warning
            "mr.find_holes(V, np.asarray(s.faces))\n")
    quiet = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           timeout=120)
    assert quiet.returncode == 0 and quiet.stderr == "", quiet.stderr
    loud = subprocess.run([sys.executable, "-c", "import logging; logging.basicConfig()\n" + code],
                          capture_output=True, text=True, timeout=120)
    assert "unreferenced" in loud.stderr


def test_metrics_json_stays_json_and_noise_refuses_unreadable_levels(tmp_path, capsys):
    """metrics --json prints one JSON document on stdout (its note about connectivity goes to
    stderr); noise refuses a level whose result no command would read (1e300 wrote coordinates
    of 3.7e299, then metrics printed overflow warnings and NaN)."""
    import json

    a = data_path("fandisk.ply")
    b = tmp_path / "b.ply"
    m = read_mesh(a)
    mr.write_mesh(b, m.V[::-1].copy(), len(m.V) - 1 - m.F)  # the same mesh, numbered backwards
    assert main(["metrics", "--json", str(a), str(b)]) == 0
    cap = capsys.readouterr()
    vals = json.loads(cap.out)
    assert "mean distance" in vals and "same connectivity" in cap.err
    out = tmp_path / "n.ply"
    assert main(["noise", str(a), str(out), "--gamma", "1e300"]) == 2
    assert "beyond" in capsys.readouterr().err and not out.exists()


@pytest.mark.parametrize("cmd", ["render", "view", "report"])
@pytest.mark.parametrize("bad", ["-5", "nan", "500", "inf"])
def test_sharp_threshold_is_an_angle(tmp_path, capsys, cmd, bad):
    """--sharp-threshold is checked as --th is, before any work (-5 marked every edge sharp,
    nan / 500 / inf none, all with exit 0)."""
    out = {"render": "o.png", "view": "o.html", "report": "o.html"}[cmd]
    argv = [cmd, str(data_path("spot.ply"))] + (["-o"] if cmd == "view" else []) + [
        str(tmp_path / out), f"--sharp-threshold={bad}"]
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2 and "angle in degrees" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_quality_line_of_a_patch_without_inner_vertices():
    from meshrepair.fill.quality import quality_line

    q = {"seam_deg": 3.0, "surround_deg": 2.0, "curvature_ratio": float("nan")}
    assert "n/a" in quality_line(q) and "nan" not in quality_line(q)
