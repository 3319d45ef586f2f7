"""Every option validated (finite, in range) with a message naming it, before any work; resource
guards with the numbers in the message (issue 11). Hole filling's own options are tested with
fill.py."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import meshrepair as mr
from meshrepair.cli import main
from meshrepair.complete.api import complete
from meshrepair.errors import MeshRepairError
from meshrepair.io import write_mesh
from meshrepair.metrics import distances, msae, point_to_surface, vertex_error
from meshrepair.model.noise import add_noise
from meshrepair.model.solver import ADMMSolver, SolverOptions, Stage
from meshrepair.options import check_bool, check_choice, check_int, check_number
from meshrepair.render import render_mesh

NAN, INF = float("nan"), float("inf")


@pytest.fixture(scope="module")
def sphere():
    m = trimesh.creation.icosphere(2)
    return np.asarray(m.vertices), np.asarray(m.faces, dtype=np.int64)


def test_checkers():
    assert check_number("x", np.float32(0.5), low=0, high=1) == 0.5
    assert check_int("n", 3.0, low=0) == 3 and check_int("n", np.int64(2)) == 2
    assert check_number("x", None, allow_none=True) is None
    for bad in (NAN, INF, -INF, "1", True, None, [1.0]):
        with pytest.raises(MeshRepairError, match=r"^x must be a finite number"):
            check_number("x", bad)
    with pytest.raises(MeshRepairError, match=r"x must be a finite number in \(0, 1\], got 0"):
        check_number("x", 0, low=0, high=1, low_open=True)
    for bad in (NAN, 1.5, -1, "2", True):
        with pytest.raises(MeshRepairError, match=r"^n must be an integer >= 0"):
            check_int("n", bad, low=0)
    with pytest.raises(MeshRepairError, match="mode must be one of 'a', 'b', got 'c'"):
        check_choice("mode", "c", ("a", "b"))
    with pytest.raises(MeshRepairError, match="flag must be True or False"):
        check_bool("flag", "yes")


@pytest.mark.parametrize("kw,name", [
    ({"tol": NAN}, "tol"), ({"tol": 0}, "tol"), ({"tol": -1e-3}, "tol"),
    ({"inner_iters": -1}, "inner_iters"), ({"inner_iters": 0}, "inner_iters"),
    ({"inner_iters": 2.5}, "inner_iters"), ({"inner_iters": 10**9}, "inner_iters"),
    ({"feature_iters": 10**9}, "feature_iters"), ({"robust_iters": 10**9}, "robust_iters"),
    ({"lam": NAN}, "lam"), ({"lam": -1}, "lam"), ({"lam": INF}, "lam"),
    ({"th": NAN}, "th"), ({"th": 0}, "th"), ({"th": 200}, "th"), ({"th": True}, "th"),
    ({"a": NAN}, "a"), ({"a": 0}, "a"),
    ({"robust_iters": NAN}, "robust_iters"), ({"robust_iters": -2}, "robust_iters"),
    ({"feature_iters": 1.5}, "feature_iters"), ({"feature_iters": INF}, "feature_iters"),
    ({"mask_update_every": -1}, "mask_update_every"),
    ({"min_feature_edges": NAN}, "min_feature_edges"), ({"min_feature_edges": 0},
                                                        "min_feature_edges"),
    ({"inner_solver": "newton"}, "inner_solver"), ({"n_solver": "magic"}, "n_solver"),
    ({"unfold": "no"}, "unfold"), ({"callback": 3}, "callback"),
    ({"stages": (Stage(a=NAN, eps=1.2, beta2_ratio=1.0),)}, "stage a"),
    ({"stages": (Stage(a=1.0, eps=NAN, beta2_ratio=1.0),)}, "eps"),
    ({"stages": (Stage(a=1.0, eps=1.2, beta2_ratio=1.0, relax=-1),)}, "relax"),
    ({"stages": (Stage(a=1.0, eps=1.2, beta2_ratio=1.0, max_iter=-1),)}, "max_iter"),
])
def test_denoise_options(sphere, kw, name):
    V, F = sphere
    with pytest.raises(MeshRepairError, match=rf"^(invalid stage .*: )?(stage )?{name}\b.*must"):
        mr.denoise(V, F, **kw)


def test_denoise_checks_options_before_the_mesh():
    # a bad option is reported even when the mesh is not looked at yet
    with pytest.raises(MeshRepairError, match="tol"):
        mr.denoise(np.eye(3), np.array([[0, 1, 2]]), tol=NAN)


@pytest.mark.parametrize("kw,name", [
    ({"tol": NAN}, "tol"), ({"inner_iters": -1}, "inner_iters"), ({"n_rtol": 2}, "n_rtol"),
    ({"willmore_weight": NAN}, "willmore_weight"), ({"mask_source": "X"}, "mask_source"),
    ({"precondition": 1}, "precondition"), ({"stages": ()}, "stage"),
])
def test_solver_options(sphere, kw, name):
    _, F = sphere
    with pytest.raises(MeshRepairError, match=name):
        ADMMSolver(F, int(F.max()) + 1, options=SolverOptions(**kw))


@pytest.mark.parametrize("kw,name", [
    ({"strip_rings": NAN}, "strip_rings"), ({"strip_rings": 0}, "strip_rings"),
    ({"iterations": -1}, "iterations"), ({"tol": NAN}, "tol"), ({"th": NAN}, "th"),
    ({"a": -1}, "a"), ({"lam": NAN}, "lam"), ({"relax": NAN}, "relax"),
    ({"max_size_ratio": 0.5}, "max_size_ratio"), ({"mask_update_every": NAN},
                                                  "mask_update_every"),
    ({"icp_rings": -1}, "icp_rings"), ({"allow_scale": "yes"}, "allow_scale"),
    ({"hole": NAN}, "hole"),
])
def test_complete_options(sphere, kw, name):
    V, F = sphere
    args = {"region": [0, 1, 2], **kw}
    if "hole" in kw:
        args.pop("region")
        keep = np.ones(len(F), bool)
        keep[:3] = False
        F = F[keep]
    with pytest.raises(MeshRepairError, match=name):
        complete(V, F, template=(V, F[:10]), **args)


def test_noise_and_metrics_options(sphere):
    V, F = sphere
    for g in (NAN, -0.1, INF):
        with pytest.raises(MeshRepairError, match="gamma"):
            add_noise(V, F, g)
    with pytest.raises(MeshRepairError, match="seed"):
        add_noise(V, F, 0.1, seed=-1)
    Vn = V.copy()
    Vn[3] = NAN
    with pytest.raises(MeshRepairError, match="non-finite"):
        distances(Vn, F, V, F)
    with pytest.raises(MeshRepairError, match="non-finite"):
        point_to_surface(Vn, V, F)
    with pytest.raises(MeshRepairError, match="non-finite"):
        msae(Vn, V, F)
    with pytest.raises(MeshRepairError, match="non-finite"):
        vertex_error(V, Vn)
    with pytest.raises(MeshRepairError, match="per_face"):
        distances(V, F, V, F, per_face=9)
    with pytest.raises(MeshRepairError, match="F"):
        distances(V, F + 1000, V, F)


def test_render_options_and_size_guard(sphere):
    V, F = sphere
    for kw, name in (({"azimuth": NAN}, "azimuth"), ({"elevation": INF}, "elevation"),
                     ({"width": NAN}, "width"), ({"supersample": 1.5}, "supersample")):
        with pytest.raises(MeshRepairError, match=name):
            render_mesh(V, F, **kw)
    # refused up front with the numbers (used to try to allocate 298 GiB)
    with pytest.raises(MeshRepairError, match=r"200000 x 200000 .* 40,000,000,000 raster pixels"):
        render_mesh(V, F, width=200000, height=200000)


def test_cli_reports_bad_option_values(tmp_path, sphere, capsys):
    V, F = sphere
    src = write_mesh(tmp_path / "s.ply", V, F)
    out = tmp_path / "o.ply"
    for opt, val, name in (("--tol", "nan", "tol"), ("--th", "nan", "th"),
                           ("--lam", "-1", "lam"), ("--feature-iters", "-3", "feature_iters")):
        assert main(["denoise", str(src), str(out), "-q", opt, val]) == 2
        err = capsys.readouterr().err
        assert f"error: {name}" in err, err
    assert main(["noise", str(src), str(out), "--gamma", "nan"]) == 2
    assert "gamma" in capsys.readouterr().err
    assert main(["render", str(src), str(tmp_path / "a.png"), "--azimuth", "nan"]) == 2
    assert "azimuth" in capsys.readouterr().err
    assert not out.exists() and not (tmp_path / "a.png").exists()
