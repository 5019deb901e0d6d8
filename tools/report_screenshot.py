"""Render the quick-start report in headless Chromium, check it reads at a glance, screenshot it.

    python tools/report_screenshot.py                       # build, check, print the timing
    python tools/report_screenshot.py --screenshot docs/figures/report.png

Runs ``inserr run analyses/quickstart/scenario.toml`` as a user would (a whole process,
timed), opens the ``report.html`` it wrote in headless Chromium (Debian's ``chromium``
and ``chromedriver``, driven with Selenium) in a 1280 x 1000 window, and checks
what the issue asks of a report an engineer reads at a glance:

* every figure loaded and shown at 100 % (its displayed width is its own width, so
  its 7-11 pt text is legible without zooming), with a caption;
* the version of inserr and the scenario's SHA-256 are on the page;
* the set-up table holds the whole scenario, the initial errors included;
* the comparison table's columns say "error" and carry units; tilts in arcsec and
  heading in arcmin in tables and figures alike;
* the budget table has readable source names and a root-sum-square total row, and
  its figure is there;
* the data files (``timeseries.csv``, ``budget.csv``) are linked.

The figures themselves (titles, one colour per scheme, legends outside the data,
attitude errors one row per scheme) are checked on the Figure objects by
``tests/test_notebook.py``; the screenshot lets a person look.

Requires ``chromium``, ``chromedriver`` (``apt-get install chromium chromium-driver``)
and ``pip install selenium``. Exit status 1 when a check fails.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
QUICKSTART = ROOT / "analyses" / "quickstart" / "scenario.toml"

#: Chromium flags: headless as root, and no background traffic on a closed network.
FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--window-size=1280,1000",
    "--force-device-scale-factor=1",
)


def build_report(out: Path) -> tuple[float, float]:
    """Run ``inserr run`` on the quick-start scenario; (wall s, CPU s of the child)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "INSERR_NO_PROGRESS": "1"}
    before = os.times()
    t0 = time.perf_counter()
    subprocess.run(
        [
            sys.executable,
            "-m",
            "inserr",
            "run",
            str(QUICKSTART.relative_to(ROOT)),
            "--out",
            str(out),
        ],
        check=True,
        cwd=ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
    )
    wall = time.perf_counter() - t0
    after = os.times()
    cpu = (after.children_user - before.children_user) + (
        after.children_system - before.children_system
    )
    return wall, cpu


def open_page(html: Path):
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for flag in FLAGS:
        options.add_argument(flag)
    options.add_argument(f"--user-data-dir={tempfile.mkdtemp(prefix='inserr-chromium-')}")
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    driver.get(html.as_uri())
    return driver


CHECK_JS = r"""
const imgs = [...document.images].map(i => ({
  alt: i.alt, complete: i.complete, natural: i.naturalWidth, shown: i.getBoundingClientRect().width,
  caption: (i.closest('figure')?.querySelector('figcaption')?.textContent || '').trim()}));
const tables = [...document.querySelectorAll('table')].map(t =>
  [...t.rows].map(r => [...r.cells].map(c => c.textContent.trim())));
const links = [...document.querySelectorAll('a')].map(a => a.getAttribute('href'));
return {imgs, tables, links, text: document.body.innerText, width: window.innerWidth};
"""


def checks(page: dict, version: str) -> list[str]:
    """The failed checks (empty when the page reads at a glance)."""
    bad = []
    for img in page["imgs"]:
        if not img["complete"] or img["natural"] == 0:
            bad.append(f"figure {img['alt']} did not load")
        elif abs(img["shown"] - img["natural"]) > 1:
            bad.append(f"figure {img['alt']} shown at {img['shown']:.0f} of {img['natural']} px")
        if img["alt"] != "error_budget" and not img["caption"] and img["alt"] != "":
            bad.append(f"figure {img['alt']} has no caption")
    text = page["text"]
    if f"inserr {version}" not in text or "SHA-256" not in text:
        bad.append("version or scenario SHA-256 missing")
    setup = next((t for t in page["tables"] if t and t[0] == ["item", "value"]), None)
    if setup is None:
        bad.append("no set-up table")
    else:
        items = [r[0] for r in setup[1:]]
        for want in ("initial attitude error", "initial velocity error", "ARW / VRW", "site"):
            if not any(i.startswith(want) for i in items):
                bad.append(f"set-up table lacks {want}")
    results = next((t for t in page["tables"] if t and t[0][0] == "scheme"), None)
    if results is None:
        bad.append("no results table")
    else:
        for col in results[0][1:]:
            if "(" not in col:
                bad.append(f"results column {col!r} has no unit")
            if "error" not in col and "motor" not in col:
                bad.append(f"results column {col!r} does not say error")
        if not any("arcmin" in c for c in results[0]):
            bad.append("heading error not in arcmin")
    budget = next((t for t in page["tables"] if t and t[0][:2] == ["source", "type"]), None)
    if budget is None:
        bad.append("no budget table")
    else:
        if budget[-1][0] != "total (root-sum-square)":
            bad.append("budget table has no total row")
        if any("_" in r[0] for r in budget[1:]):
            bad.append("budget table shows internal source names")
    if not any(i["alt"] == "error_budget" for i in page["imgs"]):
        bad.append("no budget figure")
    for name in ("timeseries.csv", "budget.csv"):
        if name not in page["links"]:
            bad.append(f"{name} not linked")
    return bad


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--screenshot", type=Path, help="save the first screen (1280 x 1000) here")
    ap.add_argument("--full", type=Path, help="save the whole page here")
    ap.add_argument(
        "--colors",
        type=int,
        default=0,
        help="quantize saved screenshots to this many colours (smaller files; needs Pillow)",
    )
    ap.add_argument("--out", type=Path, help="report directory (default: a temporary one)")
    args = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    from inserr import __version__

    out = args.out or Path(tempfile.mkdtemp(prefix="inserr-report-")) / "quickstart_report"
    wall, cpu = build_report(out)
    load = os.getloadavg()[0]
    print(f"inserr run {QUICKSTART.relative_to(ROOT)}: {wall:.2f} s wall, {cpu:.2f} s CPU")
    print(f"load average (1 min) {load:.2f} on {os.cpu_count()} CPUs")
    driver = open_page(out / "report.html")
    try:
        page = driver.execute_script(CHECK_JS)
        print(
            f"window {page['width']} px wide, {len(page['imgs'])} figures, "
            f"{len(page['tables'])} tables"
        )
        if args.screenshot:
            args.screenshot.parent.mkdir(parents=True, exist_ok=True)
            driver.save_screenshot(str(args.screenshot))
            print(f"screenshot: {args.screenshot}")
        if args.full:
            height = driver.execute_script("return document.body.scrollHeight")
            driver.set_window_size(1280, height + 100)
            driver.save_screenshot(str(args.full))
            print(f"full page: {args.full}")
    finally:
        driver.quit()
    if args.colors:
        from PIL import Image

        for path in (args.screenshot, args.full):
            if path is not None:
                Image.open(path).convert("RGB").quantize(args.colors).save(path, optimize=True)
    bad = checks(page, __version__)
    for b in bad:
        print(f"FAIL: {b}")
    print("report checks: " + ("all passed" if not bad else f"{len(bad)} failed"))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
