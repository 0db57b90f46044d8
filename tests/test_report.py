"""The reproduction's figures and HTML report on a short run: one name per controller
everywhere, figures a reader can use (units on every axis, markers that do not hide
each other), files in each format, and the page checked in a real headless browser
(Chromium): nothing overflows the window outside a table's own scroll box, and every
image loads and has alt text. The browser's screenshots are kept in the test's
temporary directory."""

from __future__ import annotations

import contextlib
import html
import io
import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

from flexarm.cli import main
from flexarm.figures import FigureFormat, figure_bytes
from flexarm.studies.reproduction import CONTROLLER_KINDS, reproduce
from flexarm.studies.reproduction.beyond import ROWS, Beyond
from flexarm.studies.reproduction.html import DISPLAY_PX_PER_INCH
from flexarm.studies.reproduction.report import (
    FIGURE_SIZES,
    FIGURES,
    OUTPUT_FILES,
    output_files,
)
from helpers.reproduction import row_result

MAGIC = {"png": b"\x89PNG\r\n\x1a\n", "pdf": b"%PDF-", "svg": b"<?xml"}


def _beyond() -> Beyond:
    """The study beyond the paper, made by hand (its own test runs it)."""

    def row(law, sensor, name, rms):
        return row_result(law, sensor, name, rms, torque=41.234, diverged_at=1.25)

    rows = [row("lqg default", s, r.name, 0.0123) for s in ("tip", "point:1:0.5") for r in ROWS]
    rows += [
        row("reflected", "tip", r.name, None if i == 1 else 0.0456) for i, r in enumerate(ROWS)
    ]
    rows += [row(f"lqg fuzzy ks {k}", s, "nominal", 0.011) for k in (1, 10) for s in ("tip",)]
    rows += [row("lqg gain 2", s, "nominal", 0.012) for s in ("tip", "point:1:0.5")]
    rows += [row("lqg fuzzy ks 1", "point:1:0.5", "nominal", 0.013)]
    growth = {"tip": {"nominal": -0.5, "3 modes, clamped-free": 0.25}}
    return Beyond({"tip": "default", "point:1:0.5": "default"}, rows, 0.84, [], growth)


@pytest.fixture(scope="module")
def study():
    rep = reproduce(
        duration=0.1,
        ks_range=(0.0, 10.0),
        laws=("scaled",),
        workers=2,
        progress=False,
        beyond=False,
    )
    rep.beyond = _beyond()
    return rep


@pytest.fixture(scope="module")
def written(study, tmp_path_factory):
    """The report as ``flexarm reproduce --format svg --dpi 72 --json`` writes it (the
    runs are the study's: the command's call of the library is replaced), and what the
    command printed."""
    import flexarm.studies.reproduction as package

    out = tmp_path_factory.mktemp("report") / "results"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(package, "reproduce", lambda **kw: study)
        argv = ["reproduce", "--out", str(out), "--format", "svg", "--dpi", "72", "--json"]
        with contextlib.redirect_stdout(io.StringIO()) as stdout:
            status = main(argv)
    assert status == 0
    return out, json.loads(stdout.getvalue())


# ------------------------------------------------------------------ names
def test_one_name_per_controller_in_json_console_figures_and_report(study, written):
    names = set(CONTROLLER_KINDS)
    assert names == {"pd", "fuzzy"}
    assert {c["controller"] for c in study.summary()["cases"]} == names
    rows = [ln for ln in study.text().splitlines() if re.match(r"  (pd|fuzzy) {2,}", ln)]
    assert [ln.split()[0] for ln in rows] == [c.case.controller for c in study.cases]
    titles = [ax.get_title() for ax in study.draw("tracking").axes]
    assert [t.split(",")[0] for t in titles] == [c.case.controller for c in study.cases]
    page = (written[0] / "report.html").read_text()
    cells = re.findall(r"<tr><td>(\w+)</td>", page)  # each table's first column
    assert set(cells) >= names and "jt-pd" not in page and "nonadaptive PD" not in page
    for c in study.cases:  # the simulator's record of the law is the same name
        assert c.result.info["controller"] == c.case.controller


# ------------------------------------------------------------------ figures
@pytest.mark.parametrize("name", FIGURES)
def test_every_figure_is_readable_at_its_width(study, name, assert_readable):
    assert_readable(study.draw(name), FIGURE_SIZES[name][0])


def test_sensitivity_markers_do_not_hide_each_other(study):
    """Series with equal errors (the encoders read the same under both sensor models)
    are shifted apart along ks, with their own markers."""
    fig = study.draw("sensitivity")
    for ax in fig.axes:
        series = [line for line in ax.get_lines() if line.get_marker() not in ("None", "", None)]
        points = [
            (round(x, 9), line.get_marker())
            for line in series
            for x, y in zip(line.get_xdata(), line.get_ydata(), strict=True)
            if np.isfinite(y)
        ]
        xs = [x for x, _ in points]
        assert len(xs) == len(set(xs)), "two markers at one place"
        markers = {line.get_marker() for line in series if line.get_marker() != "x"}
        assert len(markers) == len(
            {line.get_label() for line in series if line.get_marker() != "x"}
        )


def test_figure_files_in_each_format(study):
    assert output_files() == OUTPUT_FILES
    assert output_files("pdf")[3:] == tuple(f"{name}.pdf" for name in FIGURES)
    fig = study.draw("sensitivity")  # the whole report in SVG: the command-line test below
    assert figure_bytes(fig, FigureFormat("pdf", 100)).startswith(MAGIC["pdf"])


def test_the_page_is_built_for_people(written):
    page = (written[0] / "report.html").read_text()
    assert "<meta name='viewport'" in page and "overflow-x:auto" in page
    tables = page.count("<table>")
    # the matrix, 2 studies, the converged arm (its runs, its verdicts), beyond
    assert tables == page.count("<div class='scroll'><table>") == 6
    headers = re.findall(r"<th scope='col'>(.*?)</th>", page)
    for unit in ("RMS error (mm)", "delay (ms)", "largest Re(pole) (rad/s)", "max torque (N m)"):
        assert html.escape(unit) in headers
    assert not any("_m" in h or "_s" in h for h in headers)  # no JSON keys as headers
    # numbers rounded to what they mean: no cell with more than three significant figures
    cells = re.findall(r"<td class='n'>([-0-9.]+)</td>", page)
    assert cells and all(len(c.lstrip("-0.").replace(".", "").rstrip("0")) <= 3 for c in cells)
    imgs = re.findall(r"<img ([^>]*)>", page)
    assert len(imgs) == len(FIGURES)
    for attrs in imgs:
        alt = html.unescape(re.search(r"alt='([^']*)'", attrs).group(1))
        assert len(alt) > 100 and ("(m)" in alt or "(mm" in alt), alt  # what it shows, units
        width = int(re.search(r"width='(\d+)'", attrs).group(1))
        assert width <= 1100  # at most the page's width, shown at 150 px per inch


# ------------------------------------------------------------------ the browser
CHECK = """<script>
window.addEventListener("load", () => {
  const vw = document.documentElement.clientWidth;
  const box = (el) => {
    for (let p = el.parentElement; p && p !== document.body; p = p.parentElement) {
      const o = getComputedStyle(p).overflowX;
      if (o === "auto" || o === "scroll" || o === "hidden") return p;
    }
    return null;
  };
  const overflow = [];
  for (const el of document.body.querySelectorAll("*")) {
    const r = el.getBoundingClientRect();
    if ((r.width === 0 && r.height === 0) || (r.right <= vw + 0.5 && r.left >= -0.5)) continue;
    const b = box(el);
    if (b && b.getBoundingClientRect().right <= vw + 0.5) continue;
    const where = `${Math.round(r.left)}..${Math.round(r.right)}`;
    overflow.push(`${el.tagName.toLowerCase()} ${el.className} ${where}`);
  }
  const images = Array.from(document.images).map((i) => ({
    alt: i.alt, loaded: i.complete && i.naturalWidth > 0,
    shown: Math.round(i.getBoundingClientRect().width),
  }));
  const out = document.createElement("pre");
  out.id = "flexarm-check";
  out.textContent = JSON.stringify({
    viewport: vw, page: document.documentElement.scrollWidth,
    height: document.documentElement.scrollHeight, overflow, images,
  });
  document.body.appendChild(out);
});
</script>"""


def _chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        found = shutil.which(name)
        if found:
            return found
    return None


CHROMIUM = _chromium()
needs_chromium = pytest.mark.skipif(
    CHROMIUM is None,
    reason="Chromium is not installed (Debian: apt-get install chromium; .ci/run installs it)",
)


def _browse(page: Path, profile: Path, width: int, *args: str) -> str:
    """Run headless Chromium on ``page`` at ``width`` CSS pixels; its stdout."""
    cmd = [
        str(CHROMIUM),
        "--headless",
        "--no-sandbox",  # as root in a container
        "--disable-gpu",
        "--hide-scrollbars",
        "--no-first-run",
        "--disable-extensions",
        f"--user-data-dir={profile}",
        "--virtual-time-budget=10000",  # until the page has loaded, images decoded
        *args,
        page.as_uri(),
    ]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=False)
    assert res.returncode == 0, res.stderr[-2000:]
    return res.stdout


def _check(page: Path, tmp: Path, width: int, height: int = 900) -> dict:
    """The page as the browser lays it out at ``width``: the check's findings."""
    probe = tmp / f"probe-{page.stem}-{width}.html"
    probe.write_text(page.read_text().replace("</body>", CHECK + "</body>"))
    dom = _browse(probe, tmp / "profile", width, f"--window-size={width},{height}", "--dump-dom")
    found = re.search(r'<pre id="flexarm-check">(.*?)</pre>', dom, flags=re.S)
    assert found, dom[-2000:]
    return json.loads(html.unescape(found.group(1)))


@needs_chromium
@pytest.mark.parametrize("width", [1280, 500])  # a desktop, and Chromium's narrowest
def test_the_report_in_a_browser(written, tmp_path, width):
    page = written[0] / "report.html"
    got = _check(page, tmp_path, width)
    assert got["viewport"] == width
    assert got["overflow"] == [], got["overflow"]  # wide tables scroll in their own box
    assert got["page"] <= width  # the page itself never scrolls sideways
    assert len(got["images"]) == len(FIGURES)
    for image in got["images"]:
        assert image["loaded"] and image["alt"], image
        assert 0 < image["shown"] <= width
    if width < 1280:
        return
    shot = tmp_path / f"report-{width}.png"  # the artefact: the whole page as drawn
    _browse(
        page,
        tmp_path / "profile",
        width,
        f"--window-size={width},{min(got['height'], 16000)}",
        f"--screenshot={shot}",
    )
    assert shot.read_bytes().startswith(MAGIC["png"])
    print(f"screenshot of the report: {shot}")


@needs_chromium
def test_the_browser_check_sees_a_broken_image_and_an_overflow(tmp_path):
    """The check itself can fail: an image that does not decode and a wide table
    outside any scroll box are both reported."""
    page = tmp_path / "bad.html"
    page.write_text(
        "<!DOCTYPE html><html><body><p>fine</p>"
        "<img src='data:image/png;base64,iVBORw0KGgo=' alt='broken'>"
        f"<table><tr><td style='white-space:nowrap'>{'wide ' * 200}</td></tr></table>"
        "<div style='overflow-x:auto'><table><tr><td style='white-space:nowrap'>"
        f"{'boxed ' * 200}</td></tr></table></div></body></html>"
    )
    got = _check(page, tmp_path, 800)
    assert [i["loaded"] for i in got["images"]] == [False]
    assert got["overflow"] and all("boxed" not in o for o in got["overflow"])
    assert any(o.startswith("table") for o in got["overflow"]) and got["page"] > 800


# ------------------------------------------------------------------ the command line
def test_reproduce_writes_figures_in_the_format_asked(written):
    out, summary = written
    files = summary["files"]  # the files actually written
    assert files == list(output_files("svg")) and sorted(files) == sorted(os.listdir(out))
    for name in FIGURES:
        assert (out / f"{name}.svg").read_bytes().startswith(MAGIC["svg"])
    page = (out / "report.html").read_text()  # PNG copies in the page, at its resolution
    assert page.count("data:image/png;base64,") == len(FIGURES)
    width = re.search(r"<img [^>]*width='(\d+)'", page).group(1)
    assert int(width) == round(FIGURE_SIZES["tracking"][0] * DISPLAY_PX_PER_INCH)
