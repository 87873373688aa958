"""Screenshot an HTML report of `corrugation` (predict, sweep, study) in headless Chromium.

The report is a static page with its plots beside it; this renders it as a browser shows it,
so that a change to the report's layout or plots can be looked at without opening a desktop
browser (on a server, in CI, over SSH).

Set-up (once): a Chromium (Debian/Ubuntu: `apt-get install chromium`) and Playwright's Python
package without its own browser download (`pip install playwright`).

    python examples/report_screenshot.py RUN/report.html report.png
    python examples/report_screenshot.py RUN/report.html shots/report.png --tile-height 1600

writes the whole page as one PNG, or with `--tile-height` as numbered tiles of that height
(px) beside it (`report-00.png`, `report-01.png`, ...), which image viewers that shrink tall
images show at full size.
"""

import argparse
import math
import os
import pathlib
import sys

BROWSER_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--no-first-run",
    # on a machine without outside network these keep Chromium from retrying connections
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("report", type=pathlib.Path, help="the report's HTML file")
    ap.add_argument("out", type=pathlib.Path, help="the PNG to write")
    ap.add_argument("--width", type=int, default=1280, help="page width (px), default 1280")
    ap.add_argument(
        "--tile-height",
        type=int,
        default=0,
        help="write tiles of this height (px) instead of one image; 0 (default) for one image",
    )
    ap.add_argument(
        "--browser",
        default=os.environ.get("CHROMIUM", "/usr/bin/chromium"),
        help="the Chromium executable (default $CHROMIUM or /usr/bin/chromium)",
    )
    a = ap.parse_args()
    if not a.report.is_file():
        sys.exit(f"{a.report}: no such file (in its --out folder predict writes report.html, sweep report.html, study study.html)")
    if not pathlib.Path(a.browser).is_file():
        sys.exit(f"{a.browser}: no Chromium there (apt-get install chromium, or --browser PATH)")
    if not 320 <= a.width <= 4000:
        sys.exit(f"--width {a.width}: expected 320-4000 px")
    if a.tile_height and not 200 <= a.tile_height <= 20000:
        sys.exit(f"--tile-height {a.tile_height}: expected 0 or 200-20000 px")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        sys.exit("Playwright is not installed: pip install playwright (no browser download needed)")

    a.out.parent.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=a.browser, args=BROWSER_ARGS)
        page = browser.new_page(viewport={"width": a.width, "height": 900})
        page.goto(a.report.resolve().as_uri())
        page.wait_for_load_state("load")
        if a.tile_height == 0:
            page.screenshot(path=str(a.out), full_page=True)
            written = [a.out]
        else:
            height = page.evaluate("document.documentElement.scrollHeight")
            written = []
            for i in range(math.ceil(height / a.tile_height)):
                y = i * a.tile_height
                clip = {"x": 0, "y": y, "width": a.width, "height": min(a.tile_height, height - y)}
                path = a.out.with_name(f"{a.out.stem}-{i:02d}{a.out.suffix}")
                page.screenshot(path=str(path), full_page=True, clip=clip)
                written.append(path)
        browser.close()
    for path in written:
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
