"""Tests of meshrepair.render and the ``render`` / ``compare`` CLI sub-commands."""

from __future__ import annotations

import argparse

import numpy as np
import pytest
import trimesh

from meshrepair.errors import MeshRepairError
from meshrepair.mesh.topology import edge_topology
from meshrepair.render import compare_figure, render_mesh, render_to_file, save_png

WHITE = 250  # a pixel with all channels >= WHITE counts as background


def sphere(subdivisions: int = 3, shift=(0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    s = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    return np.asarray(s.vertices) + np.asarray(shift), np.asarray(s.faces, dtype=np.int64)


def cut_sphere() -> tuple[np.ndarray, np.ndarray]:
    """Closed unit sphere with the half x > 0 pressed flat onto the plane x = 0."""
    V, F = sphere(3)
    V = V.copy()
    V[:, 0] = np.minimum(V[:, 0], 0.0)
    return V, F


def square(z: float, size: float = 1.0, n: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Flat ``n x n`` grid in the plane ``z``, centred at the origin, normal +z."""
    t = np.linspace(-size, size, n + 1)
    X, Y = np.meshgrid(t, t, indexing="xy")
    V = np.stack([X.ravel(), Y.ravel(), np.full(X.size, z)], axis=1)
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1], idx[:-1, 1:], idx[1:, :-1], idx[1:, 1:]
    F = np.concatenate([np.stack([a, b, d], -1), np.stack([a, d, c], -1)]).reshape(-1, 3)
    return V, F


def foreground(img: np.ndarray) -> np.ndarray:
    return ~np.all(img[..., :3] >= WHITE, axis=2)


def bbox(mask: np.ndarray) -> tuple[int, int, int, int]:
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    return int(rows[0]), int(rows[-1]), int(cols[0]), int(cols[-1])


# ------------------------------------------------------------------------------------------
# render_mesh


def test_size_background_and_fit():
    V, F = sphere(3)
    img = render_mesh(V, F, width=200, height=160, colorbar=False)
    assert img.shape == (160, 200, 3) and img.dtype == np.uint8
    for r, c in [(0, 0), (0, -1), (-1, 0), (-1, -1)]:
        assert np.all(img[r, c] >= WHITE)
    r0, r1, c0, c1 = bbox(foreground(img))
    # the unit sphere is fitted to the height with a 4 % margin: diameter ~ 0.92 * 160 px
    assert abs((r1 - r0 + 1) - 0.92 * 160) <= 4
    assert abs((c1 - c0 + 1) - 0.92 * 160) <= 4
    assert abs((r0 + r1) / 2 - 79.5) <= 2 and abs((c0 + c1) / 2 - 99.5) <= 2


def test_single_triangle_coverage_matches_its_area():
    V = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [-1.0, 1.0, 0.0]])
    F = np.array([[0, 1, 2]])
    img = render_mesh(V, F, color_by="none", width=100, height=100, colorbar=False)
    fg = foreground(img)
    side = 0.92 * 100  # fitted with a 4 % margin on each side
    assert abs(fg.sum() - 0.5 * side**2) < 0.5 * side * (2 + np.sqrt(2)) / 2
    assert fg[85, 15] and not fg[15, 85]  # right angle at the lower left


def test_generic_triangle_covers_exactly_its_pixel_centres():
    from matplotlib.path import Path

    V = np.array([[0.1, 1.0, 0.0], [-1.0, -0.5, 0.3], [1.0, -0.2, -0.2]])
    F = np.array([[0, 1, 2]])
    W = H = 90
    fg = foreground(render_mesh(V, F, color_by="none", width=W, height=H, colorbar=False,
                                azimuth=0))
    # independent projection (the camera at azimuth 0): x right, y up, fitted with a 4 % margin
    lo, hi = V[:, :2].min(axis=0), V[:, :2].max(axis=0)
    ppu = 0.92 * min(W / (hi - lo)[0], H / (hi - lo)[1])
    mid = (lo + hi) / 2
    sx = (V[:, 0] - mid[0]) * ppu + W / 2
    sy = H / 2 - (V[:, 1] - mid[1]) * ppu
    yy, xx = np.mgrid[0:H, 0:W]
    centres = np.stack([xx.ravel() + 0.5, yy.ravel() + 0.5], axis=1)
    expected = Path(np.stack([sx, sy], axis=1)).contains_points(centres).reshape(H, W)
    assert expected.sum() > 1000
    assert np.count_nonzero(fg != expected) <= 3  # only ties exactly on an edge may differ


def test_no_cracks_inside_silhouette():
    V, F = sphere(4)
    img = render_mesh(V, F, width=240, height=240, colorbar=False, color_by="none")
    yy, xx = np.mgrid[0:240, 0:240]
    inside = (yy + 0.5 - 120) ** 2 + (xx + 0.5 - 120) ** 2 < (0.96 * 0.92 * 120) ** 2
    assert foreground(img)[inside].all()


def test_camera_orientation_up_and_right():
    V, F = square(0.0, n=8)
    top = V[:, 1] > 0.01  # vertices in the upper half (+y)
    right = V[:, 0] > 0.01  # vertices in the right half (+x)
    for mask, axis in ((top, "up"), (right, "right")):
        img = render_mesh(V, F, region_mask=mask, color_by="none", width=100, height=100,
                          colorbar=False).astype(int)
        blue = (img[..., 2] - img[..., 0]) > 60
        half = blue[:50].sum() if axis == "up" else blue[:, 50:].sum()
        assert blue.sum() > 500 and half > 0.95 * blue.sum()


def test_depth_occlusion_is_exact():
    """Two overlapping squares: the one nearer the camera hides the other."""
    Va, Fa = square(0.0)
    Vb, Fb = square(0.5)  # nearer to a camera on +z
    V = np.concatenate([Va, Vb])
    F = np.concatenate([Fb + len(Va), Fa])  # draw order must not matter
    s = np.concatenate([np.zeros(len(Va)), np.ones(len(Vb))])
    kw = dict(scalars=s, vmin=0.0, vmax=1.0, cmap="gray", colorbar=False, width=64, height=64)
    front = render_mesh(V, F, **kw).astype(int)
    back = render_mesh(V, F, azimuth=180, **kw).astype(int)
    assert front[32, 32].mean() > 200  # scalar 1 = white in "gray", lit face-on
    assert back[32, 32].mean() < 20  # from behind, the z = 0 square (scalar 0 = black) is in front


def test_curvature_colour_differs_between_flat_and_curved():
    V, F = cut_sphere()
    img = render_mesh(V, F, azimuth=90, width=120, height=120, colorbar=False,
                      vmin=-2.0, vmax=2.0).astype(int)
    flat = img[60, 60]  # camera on +x: the flat disc faces the viewer
    img2 = render_mesh(V, F, azimuth=-90, width=120, height=120, colorbar=False,
                       vmin=-2.0, vmax=2.0).astype(int)
    curved = img2[60, 60]  # camera on -x: the hemisphere, mean curvature 1 (convex)
    assert abs(flat[0] - flat[2]) < 15  # mid colour of coolwarm is neutral grey
    assert curved[0] - curved[2] > 60  # positive curvature is red
    # both in one picture: the right side of a 3/4 view is the flat disc, the left the sphere
    img3 = render_mesh(V, F, azimuth=45, width=120, height=120, colorbar=False,
                       vmin=-2.0, vmax=2.0).astype(int)
    r0, r1, c0, c1 = bbox(foreground(img3))
    left, right = img3[60, c0 + (c1 - c0) // 10], img3[60, c1 - (c1 - c0) // 10]
    assert left[0] - left[2] > 40
    assert abs(right[0] - right[2]) < 15


def test_robust_colour_range_ignores_outliers():
    V, F = sphere(2)
    s = np.linspace(0.0, 1.0, len(V))
    s[0] = 1e6
    img = render_mesh(V, F, scalars=s, colorbar=False, width=80, height=80, cmap="gray",
                      shading="flat")
    # without clipping nearly everything would be black; with the 2-98 % range values spread
    levels = img[foreground(img)].mean(axis=1)
    assert levels.std() > 20


def test_edge_mask_overlay_draws_dark_lines():
    V, F = sphere(2)
    nE = edge_topology(F).n_edges
    base = render_mesh(V, F, color_by="none", width=120, height=120, colorbar=False)
    em = np.zeros(nE, dtype=bool)
    em[::3] = True
    lines = render_mesh(V, F, color_by="none", width=120, height=120, colorbar=False, edge_mask=em)
    changed = np.any(base != lines, axis=2)
    assert changed.sum() > 200
    assert lines[changed].max() < 40  # drawn pixels are dark
    with pytest.raises(MeshRepairError, match="edges"):
        render_mesh(V, F, edge_mask=np.ones(nE + 1, dtype=bool))


def test_hidden_edges_are_not_drawn():
    Vf, Ff = square(0.5)  # front square, nearer to the camera on +z
    Vb, Fb = square(0.0, size=0.5)  # smaller square hidden behind it
    V, F = np.concatenate([Vf, Vb]), np.concatenate([Ff, Fb + len(Vf)])
    edges = edge_topology(F).edges
    back_edges = edges[:, 0] >= len(Vf)
    kw = dict(color_by="none", width=80, height=80, colorbar=False)
    base = render_mesh(V, F, **kw)
    assert np.array_equal(render_mesh(V, F, edge_mask=back_edges, **kw), base)
    seen = render_mesh(V, F, edge_mask=back_edges, azimuth=180, **kw)
    assert np.any(seen != render_mesh(V, F, azimuth=180, **kw))


def test_flat_and_smooth_shading_differ():
    V, F = sphere(1)
    a = render_mesh(V, F, color_by="none", shading="flat", width=80, height=80, colorbar=False)
    b = render_mesh(V, F, color_by="none", shading="smooth", width=80, height=80, colorbar=False)
    assert np.abs(a.astype(int) - b.astype(int)).max() > 20


def test_colorbar_and_title_keep_size_and_add_ink():
    V, F = sphere(2)
    plain = render_mesh(V, F, width=300, height=240, colorbar=False)
    deco = render_mesh(V, F, width=300, height=240, colorbar=True, title="sphere")
    assert deco.shape == plain.shape == (240, 300, 3)
    assert foreground(deco[:, 250:]).sum() > 200  # colour bar at the right
    assert foreground(deco[:12]).sum() > 20  # title at the top


def test_bad_inputs_raise_meshrepair_error():
    V, F = sphere(1)
    with pytest.raises(MeshRepairError, match="shape"):
        render_mesh(V[:, :2], F)
    with pytest.raises(MeshRepairError, match="face indices"):
        render_mesh(V, F + len(V))
    with pytest.raises(MeshRepairError, match="shading"):
        render_mesh(V, F, shading="toon")
    with pytest.raises(MeshRepairError, match="scalars"):
        render_mesh(V, F, color_by="scalars")
    with pytest.raises(MeshRepairError, match="per vertex"):
        render_mesh(V, F, scalars=np.zeros(3))
    with pytest.raises(MeshRepairError, match="region_mask"):
        render_mesh(V, F, region_mask=np.zeros(5, dtype=bool))


def test_save_png_and_render_to_file(tmp_path):
    from matplotlib.image import imread

    V, F = sphere(1)
    p = tmp_path / "sub" / "s.png"
    img = render_to_file(p, V, F, width=64, height=48, colorbar=False)
    assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    back = imread(p)
    assert back.shape[:2] == (48, 64)
    assert np.allclose(back[..., :3] * 255, img, atol=1)
    with pytest.raises(MeshRepairError):
        save_png(tmp_path / "x.png", np.zeros((4, 4)))


# ------------------------------------------------------------------------------------------
# compare_figure


def test_compare_figure_width_and_shared_camera(tmp_path):
    a = sphere(2)
    b = sphere(2, shift=(2.0, 0.0, 0.0))
    c = sphere(2, shift=(4.0, 0.0, 0.0))
    out = tmp_path / "cmp.png"
    w = 150
    img = compare_figure([a, b, c], ["A", "B", "C"], metrics=["m1", "m2\nline", "m3"],
                         out_path=out, width=w, height=w)
    assert out.is_file()
    assert 3 * w <= img.shape[1] <= 3 * w + w  # n panels plus a colour bar
    assert img.shape[0] > w  # titles and metric text add rows
    # same camera fitted to the union: each sphere sits further right within its panel
    centres = []
    for i in range(3):
        fg = foreground(img[:, i * w:(i + 1) * w])
        fg[: img.shape[0] // 8] = False  # ignore the title row
        fg[-img.shape[0] // 4:] = False  # and the metric text
        cols = np.flatnonzero(fg.any(axis=0))
        centres.append((cols[0] + cols[-1]) / 2)
    assert centres[0] < w / 3 and abs(centres[1] - w / 2) < 5 and centres[2] > 2 * w / 3


def test_compare_figure_scalars_and_masks_per_mesh():
    a, b = sphere(1), sphere(2)
    img = compare_figure(
        [a, b], scalars=[a[0][:, 1], b[0][:, 1]], region_mask=[None, b[0][:, 0] > 0],
        width=80, height=80, colorbar=False,
    )
    assert img.shape == (80, 160, 3)
    blue = (img[..., 2].astype(int) - img[..., 0]) > 60
    assert blue[:, :80].sum() < blue[:, 80:].sum()  # only the second panel is tinted
    with pytest.raises(MeshRepairError, match="one per mesh"):
        compare_figure([a, b], scalars=[a[0][:, 1]])


def test_degenerate_meshes_and_bad_ranges():
    V = np.zeros((3, 3))
    F = np.array([[0, 1, 2]])
    img = render_mesh(V, F, width=32, height=32, colorbar=False)  # a point: nothing to draw
    assert np.all(img >= WHITE)
    Vs, Fs = sphere(1)
    with pytest.raises(MeshRepairError, match="clip_percentile"):
        render_mesh(Vs, Fs, clip_percentile=(98, 2))
    with pytest.raises(MeshRepairError, match="vmin < vmax"):
        render_mesh(Vs, Fs, vmin=1.0, vmax=0.0)


def test_compare_figure_validates_lists():
    a = sphere(1)
    with pytest.raises(MeshRepairError, match="titles"):
        compare_figure([a, a], ["only one"])
    with pytest.raises(MeshRepairError, match="at least one"):
        compare_figure([])


@pytest.mark.parametrize("kw,msg", [
    ({"width": 0, "height": 0}, "at least 16"), ({"width": -5, "height": 10}, "at least 16"),
    ({"width": "abc"}, "width"), ({"supersample": 0}, "supersample"),
    ({"width": 5000, "height": 5000, "supersample": 3}, "raster pixels"),
    ({"width": 3000, "height": 3000}, "3 panels"),  # each fits, the figure of three does not
])
def test_compare_figure_checks_its_size_before_rendering(kw, msg):
    """compare_figure applies render_mesh's size rule (render.mesh.check_raster) to each panel
    and to the figure of all of them, before any raster is allocated."""
    a = sphere(1)
    with pytest.raises(MeshRepairError, match=msg):
        compare_figure([a, a, a], **kw)


def test_report_image_size_has_an_upper_bound(tmp_path):
    from meshrepair.report.page import write_report

    with pytest.raises(MeshRepairError, match="image_size.*raster pixels"):
        write_report(tmp_path / "r.html", title="t", output_mesh=sphere(1), image_size=100_000)
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------------------
# CLI


def _parser() -> argparse.ArgumentParser:
    from meshrepair.commands import render as cmd

    parser = argparse.ArgumentParser(prog="meshrepair")
    sub = parser.add_subparsers(dest="command", required=True)
    cmd.register(sub)
    return parser


def _write_mesh(path, V, F) -> None:
    trimesh.Trimesh(V, F, process=False).export(path)


def test_cli_render(tmp_path):
    V, F = sphere(2)
    src = tmp_path / "s.ply"
    _write_mesh(src, V, F)
    out = tmp_path / "s.png"
    args = _parser().parse_args(
        ["render", str(src), str(out), "--size", "120", "90", "--sharp-edges", "--shading",
         "smooth", "--azimuth", "30", "--elevation", "10"]
    )
    assert args.func(args) == 0
    from matplotlib.image import imread

    assert imread(out).shape[:2] == (90, 120)
    # per-vertex values from a .npy file
    npy = tmp_path / "h.npy"
    np.save(npy, V[:, 1])
    args = _parser().parse_args(["render", str(src), str(out), "--color", str(npy), "--force"])
    assert args.func(args) == 0
    # values that are not real numbers are refused, not cast (a warning, or a raw ValueError)
    for bad in (np.array(["a"] * len(V)), V[:, 1] * 1j):
        np.save(npy, bad)
        args = _parser().parse_args(["render", str(src), str(out), "--color", str(npy),
                                     "--force"])
        with pytest.raises(MeshRepairError, match="one real number"):
            args.func(args)
    # a framing radius the picture cannot resolve is refused, not drawn as a blob
    with pytest.raises(MeshRepairError, match="below 1e-9"):
        render_mesh(V, F, look_at=(0, 0, 0), radius=1e-300)


def test_cli_refuses_to_overwrite_input(tmp_path):
    p = tmp_path / "mesh.png"
    p.write_bytes(b"x")
    args = _parser().parse_args(["render", str(p), str(p)])
    with pytest.raises(MeshRepairError, match="overwrite"):
        args.func(args)
    args = _parser().parse_args(["render", str(tmp_path / "a.ply"), str(tmp_path / "a.ply")])
    with pytest.raises(MeshRepairError, match=r"\.png"):
        args.func(args)


def test_cli_compare_with_reference(tmp_path, capsys):
    V, F = sphere(2)
    rng = np.random.default_rng(0)
    noisy = V + 0.02 * rng.standard_normal(V.shape)
    paths = []
    for name, X in (("noisy", noisy), ("truth", V)):
        p = tmp_path / f"{name}.ply"
        _write_mesh(p, X, F)
        paths.append(str(p))
    out = tmp_path / "cmp.png"
    args = _parser().parse_args(
        ["compare", *paths, str(out), "--titles", "noisy", "truth", "--reference", paths[1],
         "--size", "100", "100"]
    )
    assert args.func(args) == 0
    assert out.is_file()

    from meshrepair.commands.render import reference_metrics

    m = reference_metrics(noisy, F, V, F)
    assert m["MSAE"] > 0 and m["E_V"] == pytest.approx(np.linalg.norm(noisy - V) / len(V))
    assert reference_metrics(V, F, V, F) == pytest.approx({"MSAE": 0.0, "E_V": 0.0}, abs=1e-9)
    args = _parser().parse_args(["compare", paths[0], str(out), "--titles", "a", "b", "--force"])
    with pytest.raises(MeshRepairError, match="titles"):
        args.func(args)


# ------------------------------------------------------------------------------------------
# aiming the camera, categorical colours


def grid_with_patch(n: int = 40):
    """A flat n x n grid in z = 0 (side 2) and a per-vertex mask of a small off-centre patch."""
    V, F = square(0.0, size=1.0, n=n)
    patch = (np.abs(V[:, 0] - 0.55) <= 0.1 + 1e-9) & (np.abs(V[:, 1] + 0.35) <= 0.1 + 1e-9)
    return V, F, patch


def blue_pixels(img: np.ndarray) -> np.ndarray:
    i = img.astype(int)
    return (i[..., 2] - i[..., 0]) > 60


def test_look_at_frames_the_region_so_it_fills_most_of_the_image():
    from meshrepair.render.framing import frame_vertices

    V, F, patch = grid_with_patch()
    kw = dict(region_mask=patch, color_by="none", width=160, height=120, colorbar=False)
    whole = blue_pixels(render_mesh(V, F, **kw))
    fr = frame_vertices(V, F, patch)
    assert np.allclose(fr.center, [0.55, -0.35, 0.0]) and fr.normal @ [0, 0, 1] > 0.999
    img = render_mesh(V, F, look_at=fr.center, radius=fr.radius, view_dir=-fr.normal, **kw)
    framed = blue_pixels(img)
    r0, r1, c0, c1 = bbox(framed)
    # the patch (a square of half-side 0.1, radius 0.1*sqrt(2)) fills the 120 px height:
    # side = 0.92 * 120 / sqrt(2) = 78 px, centred
    assert framed.sum() > 20 * whole.sum()
    assert abs((r1 - r0 + 1) - 0.92 * 120 / np.sqrt(2)) <= 3
    assert abs((r0 + r1) / 2 - 59.5) <= 2 and abs((c0 + c1) / 2 - 79.5) <= 2
    assert framed.mean() > 0.3  # the patch covers most of the picture around it
    with pytest.raises(MeshRepairError, match="radius"):
        render_mesh(V, F, look_at=fr.center)
    with pytest.raises(MeshRepairError, match="not both"):
        render_mesh(V, F, view_dir=[0, 0, -1], azimuth=10)
    with pytest.raises(MeshRepairError, match="radius must be"):
        render_mesh(V, F, look_at=fr.center, radius=-1.0)


def test_view_dir_matches_the_angles():
    V, F = cut_sphere()
    kw = dict(width=60, height=60, colorbar=False, vmin=-2.0, vmax=2.0)
    assert np.array_equal(render_mesh(V, F, view_dir=[-1, 0, 0], **kw),
                          render_mesh(V, F, azimuth=90, **kw))
    assert np.array_equal(render_mesh(V, F, view_dir=[0, 0, -1], **kw),
                          render_mesh(V, F, azimuth=0, **kw))


def test_look_at_clips_what_is_in_front_of_the_region():
    Va, Fa = square(0.0)  # the square to look at
    Vb, Fb = square(1.0)  # a square in front of it, nearer to the camera on +z
    V, F = np.concatenate([Va, Vb]), np.concatenate([Fa, Fb + len(Va)])
    s = np.concatenate([np.zeros(len(Va)), np.ones(len(Vb))])
    kw = dict(scalars=s, vmin=0.0, vmax=1.0, cmap="gray", colorbar=False, width=48, height=48,
              categorical=False)
    seen = render_mesh(V, F, look_at=[0, 0, 0], radius=0.5, **kw).astype(int)
    assert seen[24, 24].mean() < 20  # the z = 0 square (black), the front one clipped away
    hidden = render_mesh(V, F, look_at=[0, 0, 0], radius=0.5, clip=False, **kw).astype(int)
    assert hidden[24, 24].mean() > 200


def test_sparse_mask_gets_a_categorical_colour_bar():
    from meshrepair.render import _MASK_COLOURS, _categories

    V, F = sphere(3)
    mask = np.zeros(len(V))
    mask[:5] = 1.0  # sparse: its 2-98 % percentiles are both 0
    cats, colours = _categories(mask, "scalars", None, None, None, None)
    assert np.array_equal(cats, [0.0, 1.0]) and np.array_equal(colours, _MASK_COLOURS)
    assert _categories(V[:, 0], "scalars", None, None, None, None) is None  # continuous
    assert _categories(mask, "scalars", None, 0.0, 1.0, None) is None  # explicit range
    img = render_mesh(V, F, scalars=mask, width=300, height=240)
    bar = img[:, 212:].astype(int)  # the sphere fills the 218 x 240 px left of the bar
    orange = np.all(np.abs(bar - np.round(_MASK_COLOURS[1] * 255)) <= 2, axis=2)
    grey = np.all(np.abs(bar - np.round(_MASK_COLOURS[0] * 255)) <= 2, axis=2)
    assert orange.sum() > 200 and grey.sum() > 200  # one box per category
    # no continuous ramp: hardly any other coloured pixels in the bar
    sat = (bar.max(axis=2) - bar.min(axis=2)) > 30
    assert (sat & ~orange).sum() < 0.2 * orange.sum()
    # the surface shows the few masked vertices' faces in orange (nearest-vertex colouring)
    face = img[:, :212].astype(int)
    assert np.any((face[..., 0] - face[..., 2]) > 100)


def _holey_sphere():
    V, F = sphere(3)
    c = V[F].mean(axis=1)
    F = F[c[:, 0] < 0.8]
    used = np.unique(F)
    remap = -np.ones(len(V), np.int64)
    remap[used] = np.arange(len(used))
    return V[used], remap[F]


def test_cli_render_and_compare_frame_a_hole_and_a_region(tmp_path):
    from matplotlib.image import imread

    from meshrepair.cli import main

    V, F = _holey_sphere()
    holey = tmp_path / "holey.ply"
    _write_mesh(holey, V, F)
    filled = tmp_path / "filled.ply"
    assert main(["fill", str(holey), str(filled), "-q"]) == 0
    out = tmp_path / "hole.png"
    assert main(["render", str(holey), str(out), "--frame-hole", "0", "--size", "200", "200",
                 "--color", "none"]) == 0
    img = (imread(out)[..., :3] * 255).astype(int)
    # close up on the open cap (seen through it: the inside of the sphere), the surface covers
    # (nearly) the whole picture (measured 91 %); the whole sphere covers ~66 % of it
    assert foreground(img).mean() > 0.85
    assert main(["render", str(holey), str(out), "--size", "200", "200", "--color", "none",
                 "--view-dir=-1,0,0", "--force"]) == 0
    assert foreground((imread(out)[..., :3] * 255).astype(int)).mean() < 0.75
    # the filled patch, coloured by the 'filled' attribute (categorical), fills most of it
    out2 = tmp_path / "patch.png"
    assert main(["render", str(filled), str(out2), "--frame-region", "filled", "--color",
                 "filled", "--size", "240", "200"]) == 0
    img2 = (imread(out2)[..., :3] * 255).astype(int)
    orange = (img2[..., 0] - img2[..., 2]) > 100
    r0, r1, c0, c1 = bbox(orange[:, :170])  # left of the colour bar
    assert r1 - r0 + 1 > 0.6 * 200 and orange[:, :170].mean() > 0.25
    # compare: same camera on both, the attribute only on one mesh (grey on the other)
    out3 = tmp_path / "cmp.png"
    assert main(["compare", str(holey), str(filled), str(out3), "--frame-hole", "0",
                 "--color", "filled", "--size", "150", "150"]) == 0
    img3 = (imread(out3)[..., :3] * 255).astype(int)
    right = img3[:, 150:300]
    assert ((right[..., 0] - right[..., 2]) > 100).mean() > 0.2  # titles included
    assert ((img3[:, :150, 0] - img3[:, :150, 2]) > 100).mean() < 0.01
    assert main(["render", str(holey), str(out), "--frame-hole", "7", "--force"]) == 2
    assert main(["render", str(holey), str(out), "--look-at", "0,0,0"]) == 2
    assert main(["render", str(holey), str(out), "--frame-region", "nope"]) == 2
