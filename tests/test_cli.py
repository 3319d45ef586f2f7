"""The meshrepair command: help, demo, denoise/noise/metrics, refusal to overwrite."""

import json

import numpy as np
import pytest

from meshrepair.cli import build_parser, main
from meshrepair.io import read_mesh, write_mesh

from .bundled import bundled_mesh, data_path

SPOT = data_path("spot.ply")


def test_help_lists_commands(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    for cmd in ("denoise", "noise", "metrics", "demo"):
        assert cmd in out


def test_python_dash_m_runs_the_tool():
    """``python -m meshrepair`` is the ``meshrepair`` command (its help and exit status)."""
    import subprocess
    import sys

    ok = subprocess.run([sys.executable, "-m", "meshrepair", "--help"], capture_output=True,
                        text=True, timeout=120)
    assert ok.returncode == 0 and "denoise" in ok.stdout
    bad = subprocess.run([sys.executable, "-m", "meshrepair", "denoise", "missing.ply", "o.ply"],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode != 0 and "missing.ply" in bad.stderr


def test_noise_denoise_metrics_roundtrip(tmp_path, capsys):
    src = SPOT
    noisy = tmp_path / "noisy.ply"
    out = tmp_path / "out.ply"
    assert main(["noise", str(src), str(noisy), "--gamma", "0.2", "--seed", "3"]) == 0
    assert main(["denoise", str(noisy), str(out), "-q", "--save-mask",
                 "--log", str(tmp_path / "h.json")]) == 0
    r, _n, g = read_mesh(out), read_mesh(noisy), read_mesh(src)
    assert np.array_equal(r.F, g.F) and r.V.shape == g.V.shape
    assert "sharp" in r.vertex_attributes
    hist = json.loads((tmp_path / "h.json").read_text())
    assert len(hist["history"]) > 10
    capsys.readouterr()
    assert main(["metrics", str(out), str(src), "--json"]) == 0
    m_out = json.loads(capsys.readouterr().out)
    assert main(["metrics", str(noisy), str(src), "--json"]) == 0
    m_in = json.loads(capsys.readouterr().out)
    assert m_out["MSAE (deg^2)"] < m_in["MSAE (deg^2)"] / 5


def test_refuses_to_overwrite_input_and_existing(tmp_path, capsys):
    p = tmp_path / "m.ply"
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    write_mesh(p, V, F)
    before = p.read_bytes()
    assert main(["denoise", str(p), str(p), "-q"]) == 2
    assert "input" in capsys.readouterr().err
    assert main(["denoise", str(p), str(p), "-q", "--force"]) == 2
    assert p.read_bytes() == before
    other = tmp_path / "o.ply"
    other.write_bytes(b"keep me")
    assert main(["noise", str(p), str(other)]) == 2
    assert "--force" in capsys.readouterr().err
    assert other.read_bytes() == b"keep me"


def test_unreadable_file_is_a_clear_error(tmp_path, capsys):
    bad = tmp_path / "bad.ply"
    bad.write_text("this is not a mesh")
    assert main(["denoise", str(bad), str(tmp_path / "o.ply"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "bad.ply" in err and "error" in err


def test_demo_runs_and_reports_errors(tmp_path, capsys):
    assert main(["demo", "--outdir", str(tmp_path), "--quiet", "--no-render"]) == 0
    out = capsys.readouterr().out
    lines = {ln.split()[0]: ln.split() for ln in out.splitlines() if ln.strip()}
    noisy, den = float(lines["noisy"][1]), float(lines["denoised"][1])
    assert den < noisy / 20
    assert (tmp_path / "fandisk_denoised.ply").exists()


def test_parser_options_documented():
    p = build_parser()
    text = p.format_help()
    assert "demo" in text


def test_repair_commands_write_html_report(tmp_path):
    out, rep = tmp_path / "filled.ply", tmp_path / "run.html"
    V, F = bundled_mesh("spot.ply")
    holed = tmp_path / "holed.ply"  # spot with two holes cut out
    cut = np.linalg.norm(V[F].mean(axis=1) - V[0], axis=1) < 0.15
    cut |= np.linalg.norm(V[F].mean(axis=1) - V[1500], axis=1) < 0.1
    write_mesh(holed, V, F[~cut])
    assert main(["fill", str(holed), str(out), "--report", str(rep), "-q"]) == 0
    html = rep.read_text()
    assert "holes filled" in html and html.count("data:image/png;base64,") >= 2
    noisy, den, rep2 = tmp_path / "n.ply", tmp_path / "d.ply", tmp_path / "d.html"
    assert main(["noise", str(SPOT), str(noisy), "--gamma", "0.2"]) == 0
    assert main(["denoise", str(noisy), str(den), "-q", "--report", str(rep2)]) == 0
    assert "noise estimate" in rep2.read_text()


def _ctrl_c_at_iteration(monkeypatch, k: int = 3, *, reading: bool = False) -> dict:
    """Make the CLI's progress bar raise KeyboardInterrupt at the ``k``-th solver iteration (as
    Ctrl-C does there) of the main solve, or with ``reading`` of denoise's reading (its probe);
    returns the call counter."""
    from meshrepair.commands import common

    calls = {"n": 0}
    orig = common.ProgressBar.__call__

    def interrupt(self, entry):
        if (self.desc == "reading") == reading:
            calls["n"] += 1
            if calls["n"] == k:
                raise KeyboardInterrupt
        orig(self, entry)

    monkeypatch.setattr(common.ProgressBar, "__call__", interrupt)
    return calls


@pytest.mark.parametrize("save", [False, True])
def test_ctrl_c_stops_cleanly(tmp_path, monkeypatch, save):
    _ctrl_c_at_iteration(monkeypatch)
    out = tmp_path / "o.ply"
    args = ["denoise", str(SPOT), str(out), "-q"]
    rc = main(args + (["--save-on-interrupt"] if save else []))
    if save:
        assert rc == 0 and out.exists()
        assert read_mesh(out).V.shape == read_mesh(SPOT).V.shape
    else:
        assert rc == 130 and not out.exists()


@pytest.mark.parametrize("save", [False, True])
def test_ctrl_c_during_the_reading_writes_nothing(tmp_path, monkeypatch, capsys, save):
    """Ctrl-C while denoise reads the input (its probe, before the main solve) stops the
    command: exit 130, nothing written, even with --save-on-interrupt (there is no iterate of
    the main solve to save); the probe used to swallow it and the main solve ran anyway."""
    calls = _ctrl_c_at_iteration(monkeypatch, reading=True)
    out = tmp_path / "o.ply"
    rc = main(["denoise", str(SPOT), str(out)] + (["--save-on-interrupt"] if save else []))
    assert calls["n"] == 3 and rc == 130 and not out.exists()
    assert "interrupted" in capsys.readouterr().err


@pytest.mark.parametrize("save", [False, True])
def test_ctrl_c_during_fill_writes_nothing(tmp_path, monkeypatch, save):
    """fill (and inpaint, the same path) as denoise: Ctrl-C during the solve writes nothing and
    exits 130 (it wrote the partial iterate and exited 0), unless --save-on-interrupt."""
    import meshrepair as mr

    V, F = bundled_mesh("spot.ply")
    cut = np.linalg.norm(V[F].mean(axis=1) - V[1500], axis=1) < 0.12
    holed, out = tmp_path / "holed.ply", tmp_path / "filled.ply"
    mr.write_mesh(holed, V, F[~cut])
    calls = _ctrl_c_at_iteration(monkeypatch)
    rc = main(["fill", str(holed), str(out), "-q"] + (["--save-on-interrupt"] if save else []))
    assert calls["n"] >= 3  # the solve was interrupted
    if save:
        assert rc == 0 and out.exists()
    else:
        assert rc == 130 and not out.exists()


@pytest.mark.parametrize("fitted", [False, True])
def test_fill_fitted_flag_matches_the_library(tmp_path, fitted):
    """``fill --fitted`` passes ``fitted=True`` to :func:`meshrepair.fill_holes`: the file it
    writes holds the library's patch."""
    import meshrepair as mr

    V, F = bundled_mesh("spot.ply")
    cut = np.linalg.norm(V[F].mean(axis=1) - V[1500], axis=1) < 0.12
    holed, out = tmp_path / "holed.ply", tmp_path / "filled.ply"
    write_mesh(holed, V, F[~cut])
    src = read_mesh(holed)
    args = ["fill", str(holed), str(out), "-q"] + (["--fitted"] if fitted else [])
    assert main(args) == 0
    ref = mr.fill_holes(src.V, src.F, fitted=fitted)
    got = read_mesh(out)
    assert got.F.shape == ref.F.shape
    np.testing.assert_allclose(got.V, ref.V, atol=1e-6 * np.ptp(V, axis=0).max())
    other = mr.fill_holes(src.V, src.F, fitted=not fitted)  # the flag changes this hole's patch
    assert other.V.shape != ref.V.shape or not np.allclose(other.V, ref.V, atol=1e-4)
