"""The 3-D viewer in a real browser: Debian's Chromium, headless, WebGL in software (SwiftShader).

Run with ``pytest -q --browser -m browser`` (deselected otherwise). Needs the ``browser`` extra
(playwright, the Python driver only: no browser download) and the system Chromium at
``/usr/bin/chromium`` (``apt-get install chromium``), or ``MESHREPAIR_CHROMIUM=/path``. When
they are missing these tests FAIL, they never skip.
"""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np
import pytest
import trimesh

pytestmark = pytest.mark.browser

CHROMIUM = os.environ.get("MESHREPAIR_CHROMIUM", "/usr/bin/chromium")
ARGS = ["--headless=new", "--no-sandbox", "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader"]
READY = "() => window.meshrepairViewer && window.meshrepairViewer.state.ready " \
        "&& window.meshrepairViewer.state.frames > 0"


def holey_sphere() -> tuple[np.ndarray, np.ndarray]:
    """Unit icosphere with two holes: a big cap around +x and a small one around +y."""
    s = trimesh.creation.icosphere(subdivisions=3)
    V, F = np.asarray(s.vertices), np.asarray(s.faces, dtype=np.int64)
    c = V[F].mean(axis=1)
    keep = (c[:, 0] < 0.8) & (c[:, 1] < 0.93)
    F = F[keep]
    used = np.unique(F)
    remap = -np.ones(len(V), np.int64)
    remap[used] = np.arange(len(used))
    return V[used], remap[F]


@pytest.fixture(scope="module")
def pages(tmp_path_factory) -> dict[str, Path]:
    from meshrepair.cli import main
    from meshrepair.viewer import ViewerMesh, write_viewer

    d = tmp_path_factory.mktemp("viewer")
    V, F = holey_sphere()
    src = d / "holey.ply"
    trimesh.Trimesh(V, F, process=False).export(src)
    out = d / "filled.ply"
    assert main(["fill", str(src), str(out), "-q", "--report", str(d / "report.html")]) == 0
    assert main(["view", str(src), str(out), "-o", str(d / "view.html")]) == 0
    s = trimesh.creation.icosphere(subdivisions=4)
    write_viewer(d / "decimated.html", [ViewerMesh("big", s.vertices, s.faces)],
                 face_budget=500)
    return {"view": d / "view.html", "report": d / "report.html",
            "decimated": d / "decimated.html"}


@pytest.fixture(scope="module")
def browser():
    if not Path(CHROMIUM).exists():
        pytest.fail(f"Chromium not found at {CHROMIUM}: apt-get install chromium (or set "
                    "MESHREPAIR_CHROMIUM); browser tests fail rather than skip")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.fail("playwright is not installed: pip install -e '.[browser]'")
    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


class Viewer:
    """A loaded viewer page with its console messages and requests."""

    def __init__(self, browser, path: Path):
        self.page = browser.new_page(viewport={"width": 1280, "height": 900})
        self.errors: list[str] = []
        self.requests: list[str] = []
        self.page.on("console", lambda m: m.type in ("error", "warning") and self.errors.append(
            f"{m.type}: {m.text}"))
        self.page.on("pageerror", lambda e: self.errors.append(f"pageerror: {e}"))

        def route(r):  # offline: anything but the file itself is refused and recorded
            self.requests.append(r.request.url)
            if r.request.url.startswith(("file:", "data:", "blob:")):
                r.continue_()
            else:
                r.abort()

        self.page.route("**/*", route)
        self.page.goto(path.as_uri())
        self.page.wait_for_function(READY, timeout=60_000)

    def frames(self) -> int:
        return self.page.evaluate("window.meshrepairViewer.state.frames")

    def settle(self, before: int) -> None:
        self.page.wait_for_function("f => window.meshrepairViewer.state.frames > f", arg=before,
                                    timeout=20_000)

    def cameras(self) -> list[dict]:
        return self.page.evaluate("window.meshrepairViewer.cameras()")

    def canvas(self, i: int) -> np.ndarray:
        from matplotlib.image import imread

        png = self.page.locator(".mr-pane canvas").nth(i).screenshot()
        return (imread(io.BytesIO(png), format="png")[..., :3] * 255).astype(np.int16)

    def close(self) -> None:
        self.page.close()


@pytest.fixture
def view(browser, pages):
    v = Viewer(browser, pages["view"])
    yield v
    v.close()


def assert_same_cameras(cams: list[dict]) -> None:
    for c in cams[1:]:
        for key in ("position", "target", "quaternion"):
            assert np.allclose(c[key], cams[0][key], atol=1e-9), (key, c[key], cams[0][key])


def test_page_loads_offline_without_console_errors(view):
    assert view.errors == []
    assert [u for u in view.requests if not u.startswith("file:")] == []
    assert view.page.locator(".mr-pane canvas").count() == 2
    assert view.page.locator(".mr-error").count() == 0


def test_each_canvas_shows_the_mesh(view):
    for i in range(2):
        img = view.canvas(i)
        ink = np.any(img < 235, axis=2)  # white background
        assert ink.mean() > 0.08, f"pane {i}: only {ink.mean():.1%} of the canvas is drawn"
        assert img[ink].std() > 5  # shaded, not a flat silhouette
    # the panes follow the window: narrower window, narrower canvases, still drawn
    w0 = view.page.locator(".mr-pane canvas").nth(0).bounding_box()["width"]
    f = view.frames()
    view.page.set_viewport_size({"width": 800, "height": 900})
    view.settle(f)
    w1 = view.page.locator(".mr-pane canvas").nth(0).bounding_box()["width"]
    assert w1 < 0.75 * w0
    assert view.page.evaluate("window.meshrepairViewer.panes[0].renderer.domElement.width") \
        == round(w1)
    assert np.any(view.canvas(0) < 235, axis=2).mean() > 0.08
    assert view.errors == []


def test_cameras_stay_in_sync_after_drag_pan_and_zoom(view):
    before = view.cameras()
    assert_same_cameras(before)
    box = view.page.locator(".mr-pane canvas").nth(0).bounding_box()
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    m = view.page.mouse
    f = view.frames()
    m.move(cx, cy)
    m.down()
    for k in range(1, 11):
        m.move(cx + 12 * k, cy + 5 * k)
    m.up()
    view.settle(f)
    orbit = view.cameras()
    assert not np.allclose(orbit[0]["position"], before[0]["position"])
    assert_same_cameras(orbit)
    # pan with the right button in the second pane: both targets move together
    box1 = view.page.locator(".mr-pane canvas").nth(1).bounding_box()
    x1, y1 = box1["x"] + box1["width"] / 2, box1["y"] + box1["height"] / 2
    f = view.frames()
    m.move(x1, y1)
    m.down(button="right")
    for k in range(1, 8):
        m.move(x1 + 10 * k, y1)
    m.up(button="right")
    view.settle(f)
    pan = view.cameras()
    assert not np.allclose(pan[0]["target"], orbit[0]["target"])
    assert_same_cameras(pan)
    # zoom with the wheel
    f = view.frames()
    m.move(cx, cy)
    m.wheel(0, -400)
    view.settle(f)
    zoom = view.cameras()
    d0 = np.linalg.norm(np.subtract(pan[0]["position"], pan[0]["target"]))
    d1 = np.linalg.norm(np.subtract(zoom[0]["position"], zoom[0]["target"]))
    assert d1 < 0.95 * d0
    assert_same_cameras(zoom)
    assert view.errors == []


@pytest.mark.parametrize("toggle", ["wireframe", "shading", "colour", "highlight"])
def test_toggle_changes_the_pixels(view, toggle):
    before = view.canvas(1)
    f = view.frames()
    if toggle == "wireframe":
        view.page.check("input[data-mr=wireframe]")
    elif toggle == "shading":
        view.page.select_option("select[data-mr=shading]", "smooth")
    elif toggle == "colour":
        view.page.select_option("select[data-mr=color]", "")
    else:
        view.page.uncheck("input[data-mr=highlight]")
    view.settle(f)
    after = view.canvas(1)
    changed = np.any(np.abs(after - before) > 4, axis=2)
    assert changed.mean() > 0.002, f"{toggle}: only {changed.sum()} pixels changed"
    assert view.errors == []


def test_go_to_hole_frames_it(view):
    regions = view.page.evaluate("window.meshrepairViewer.regions")
    k = next(i for i, r in enumerate(regions) if r["name"].endswith("hole 1"))  # the small one
    before = view.cameras()
    before_img = view.canvas(0)
    f = view.frames()
    view.page.locator("button.mr-goto").nth(k).click()
    view.settle(f)
    after = view.cameras()
    assert_same_cameras(after)
    r = regions[k]
    assert np.allclose(after[0]["target"], r["center"], atol=1e-6)
    d_before = np.linalg.norm(np.subtract(before[0]["position"], before[0]["target"]))
    d_after = np.linalg.norm(np.subtract(after[0]["position"], after[0]["target"]))
    assert d_after < 0.6 * d_before  # closer: the small hole fills the view
    view_dir = np.subtract(after[0]["position"], after[0]["target"]) / d_after
    assert view_dir @ np.asarray(r["normal"]) > 0.99  # looking straight into the hole
    # close up, the surface around the hole covers the whole pane (the whole sphere did not)
    ink_before = np.any(before_img < 235, axis=2).mean()
    ink_after = np.any(view.canvas(0) < 235, axis=2).mean()
    assert ink_before < 0.8 and ink_after > 0.9, (ink_before, ink_after)
    assert view.errors == []


def test_report_page_has_a_working_viewer_and_hole_table(browser, pages):
    v = Viewer(browser, pages["report"])
    try:
        assert v.errors == []
        assert [u for u in v.requests if not u.startswith("file:")] == []
        assert v.page.locator(".mr-pane canvas").count() == 2
        assert v.page.locator("button.mr-goto").count() >= 2
        text = v.page.inner_text("body")
        assert "filled (plane" in text or "filled (" in text
        img = v.canvas(1)
        assert np.any(img < 235, axis=2).mean() > 0.08
    finally:
        v.close()


def test_decimated_copy_is_shown_and_announced(browser, pages):
    v = Viewer(browser, pages["decimated"])
    try:
        note = v.page.inner_text(".mr-decimated")
        assert "decimated" in note and "of 5,120 faces" in note
        assert np.any(v.canvas(0) < 235, axis=2).mean() > 0.08
        assert v.errors == []
    finally:
        v.close()
