"""Screenshot of the 3-D viewer for docs/viewer.md (and its load time and page size).

Fills the holes of the shared ``bunny.ply`` (5 real holes), writes ``meshrepair view`` of the
input and the result, opens the page in headless Debian Chromium (WebGL in SwiftShader), goes to
a hole and saves the viewer as a PNG::

    python benchmarks/viewer_screenshot.py --out docs/img/viewer.png [--hole 0]

Needs the ``browser`` extra (playwright) and ``apt-get install chromium``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SHARED = HERE.parents[1] / "shared" / "meshes"
ARGS = ["--headless=new", "--no-sandbox", "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader"]
READY = ("() => window.meshrepairViewer && window.meshrepairViewer.state.ready "
         "&& window.meshrepairViewer.state.frames > 0")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default=str(SHARED / "bunny.ply"))
    ap.add_argument("--out", default=str(HERE.parent / "docs" / "img" / "viewer.png"))
    ap.add_argument("--hole", type=int, default=0, help="go to this region of the list")
    ap.add_argument("--zoom-out", type=int, default=14, help="wheel steps out after going there")
    ap.add_argument("--tilt", type=int, default=90, help="then orbit by dragging up N pixels")
    ap.add_argument("--pan", type=int, default=110, help="then pan by right-dragging N px down")
    ap.add_argument("--chromium", default="/usr/bin/chromium")
    ap.add_argument("--repeat", type=int, default=3, help="page loads timed")
    args = ap.parse_args()
    from playwright.sync_api import sync_playwright

    from meshrepair.cli import main as cli

    tmp = Path(tempfile.mkdtemp(prefix="mr-viewer-shot-"))
    filled = tmp / "filled.ply"
    page_path = tmp / "view.html"
    if cli(["fill", args.mesh, str(filled), "-q"]) != 0:
        return 1
    if cli(["view", args.mesh, str(filled), "-o", str(page_path), "--titles", "input (holes)",
            "filled"]) != 0:
        return 1
    size_mb = page_path.stat().st_size / 2**20
    loads = []
    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=args.chromium, args=ARGS)
        for k in range(args.repeat):
            page = b.new_page(viewport={"width": 1400, "height": 900})
            errors: list[str] = []
            page.on("console", lambda m, e=errors: m.type == "error" and e.append(m.text))
            t0 = time.perf_counter()
            page.goto(page_path.as_uri())
            page.wait_for_function(READY, timeout=120_000)
            loads.append(time.perf_counter() - t0)
            if errors:
                print("console errors:", errors, file=sys.stderr)
                return 1
            if k < args.repeat - 1:
                page.close()
        f = page.evaluate("window.meshrepairViewer.state.frames")
        page.select_option("select[data-mr=shading]", "smooth")
        page.locator("button.mr-goto").nth(args.hole).click()
        box = page.locator(".mr-pane canvas").nth(0).bounding_box()
        page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
        for _ in range(args.zoom_out):  # some context around the hole
            page.mouse.wheel(0, 100)
            page.wait_for_timeout(50)
        if args.tilt:  # orbit: drag upwards by --tilt pixels
            x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
            page.mouse.down()
            for k in range(1, 11):
                page.mouse.move(x, y - args.tilt * k / 10)
            page.mouse.up()
        if args.pan:  # pan: right-drag down by --pan pixels
            x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
            page.mouse.move(x, y)
            page.mouse.down(button="right")
            for k in range(1, 11):
                page.mouse.move(x, y + args.pan * k / 10)
            page.mouse.up(button="right")
        page.wait_for_function("f => window.meshrepairViewer.state.frames > f", arg=f)
        page.wait_for_timeout(300)
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        page.locator("#mr-viewer").screenshot(path=args.out)
        b.close()
    print(f"page {size_mb:.2f} MB; load to first frame: median {statistics.median(loads):.2f} s "
          f"over {len(loads)} loads ({', '.join(f'{t:.2f}' for t in loads)}); wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
