"""The reproduction's report as one self-contained HTML page.

Everything is inside the page: the style sheet, and the figures as PNG data URLs,
each with alt text that says what it shows (the runs that diverged included) and
an intrinsic size, shown at 150 pixels per inch of figure (a figure two columns of
a paper wide is 1050 pixels, the page's width). Tables have human column names
with units, numbers rounded to what they mean
(:mod:`~flexarm.studies.reproduction.units`: errors in mm, three significant
figures), and each sits in its own box that scrolls sideways when the window is
narrower than the table, so that no table widens the page. A test opens the page
in headless Chromium and fails on overflow or a broken image.

Matplotlib is not needed here: the figures come as bytes.
"""

from __future__ import annotations

import base64
import html
import struct
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from .cases import CONTROLLER_DESCRIPTIONS, CONTROLLER_KINDS, MODEL_LABELS, SENSOR_LABELS, Row
from .units import MISSING, sig

if TYPE_CHECKING:
    from .cases import CaseResult
    from .report import Reproduction, Settings

__all__ = [
    "CASE_COLUMNS",
    "DISPLAY_PX_PER_INCH",
    "STYLE_SHEET",
    "Column",
    "case_table",
    "image",
    "report_page",
    "table",
]

DISPLAY_PX_PER_INCH = 150.0
"""CSS pixels per inch of figure: the size the figures are shown at (their fonts of
7-8 pt read as about 11-12 px)."""

STYLE_SHEET = (
    "*,*::before,*::after{box-sizing:border-box}"
    "body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,'DejaVu Sans',sans-serif;"
    "max-width:1100px;margin:0 auto;padding:1rem 1.25rem;line-height:1.45;color:#111;"
    "overflow-wrap:break-word}"
    "h1{font-size:1.6rem;line-height:1.25}h2{margin-top:2rem;border-bottom:1px solid #ccc}"
    ".scroll{overflow-x:auto;max-width:100%;margin:.5rem 0 1.25rem}"
    "table{border-collapse:collapse;font-size:.85rem;font-variant-numeric:tabular-nums}"
    "th,td{border:1px solid #bbb;padding:.2rem .4rem;vertical-align:top}"
    "th{background:#eee;text-align:left;font-weight:600}"
    "td{white-space:nowrap}td.n{text-align:right}td.w{white-space:normal;min-width:8.5em}"
    "figure{margin:1rem 0}img{display:block;max-width:100%;height:auto}"
    "figcaption{font-size:.9rem;color:#333;margin-top:.3rem}"
    ".supported{color:#060}.not{color:#a00}.partly{color:#8a5a00}"
)
"""The page's style: a readable column, tables in their own scroll boxes, images that
shrink with the window."""


@dataclass(frozen=True)
class Column:
    """A column of a table: its header (a name and its unit), whether it holds
    numbers (set right-aligned), and how a row's cell is written."""

    header: str
    numeric: bool
    cell: Callable[[Row], str]


def _scaled(key: str, scale: float = 1.0) -> Callable[[Row], str]:
    def cell(row: Row) -> str:
        value = row.get(key)
        return sig(scale * float(value)) if isinstance(value, int | float) else MISSING

    return cell


def _text(key: str, names: Mapping[str, str] | None = None) -> Callable[[Row], str]:
    def cell(row: Row) -> str:
        value = row.get(key)
        if value is None:
            return MISSING
        return (names or {}).get(str(value), str(value))

    return cell


def _outcome(row: Row) -> str:
    if row.get("status") == "ok":
        return "completed"
    at = row.get("diverged_at_s")
    return f"diverged at {sig(float(at))} s" if isinstance(at, int | float) else "diverged"


def _ks(row: Row) -> str:
    value = row.get("ks")
    return f"{value:g}" if isinstance(value, int | float) else MISSING


CASE_COLUMNS = (
    Column("controller", False, _text("controller")),
    Column("adaptation law", False, _text("law")),
    Column("ks (-)", True, _ks),
    Column("sensor", False, _text("sensor", SENSOR_LABELS)),
    Column("sensor model", False, _text("sensor_model")),
    Column("delay model", False, _text("delay")),
    Column("delay (ms)", True, _scaled("delay_s", 1e3)),
    Column("outcome", False, _outcome),
    Column("largest Re(pole) (rad/s)", True, _scaled("max_real_pole_rad_s")),
    Column("RMS error (mm)", True, _scaled("rms_error_m", 1e3)),
    Column("max error (mm)", True, _scaled("max_error_m", 1e3)),
    Column("max corner error (mm)", True, _scaled("corner_error_max_m", 1e3)),
    Column("residual vibration (mm)", True, _scaled("residual_vibration_m", 1e3)),
    Column("control effort (N² m² s)", True, _scaled("control_effort_N2m2s")),
)
"""The columns of the report's tables of runs (:meth:`CaseResult.row`'s keys, for people)."""


def table(
    headers: Sequence[str],
    rows: Sequence[Sequence[str]],
    numeric: Sequence[bool],
    wrap: Sequence[bool] | None = None,
) -> str:
    """A table (cells already written as text, escaped here) in its own scroll box:
    numbers right-aligned, cells on one line unless their column may ``wrap``."""
    head = "".join(f"<th scope='col'>{html.escape(h)}</th>" for h in headers)
    kinds = [
        " class='n'" if n else " class='w'" if w else ""
        for n, w in zip(numeric, wrap or [False] * len(numeric), strict=True)
    ]
    body = "".join(
        "<tr>"
        + "".join(f"<td{k}>{html.escape(v)}</td>" for v, k in zip(row, kinds, strict=True))
        + "</tr>"
        for row in rows
    )
    return (
        f"<div class='scroll'><table><thead><tr>{head}</tr></thead>"
        f"<tbody>{body}</tbody></table></div>"
    )


def case_table(cases: Sequence[CaseResult]) -> str:
    """The runs ``cases`` as a table of :data:`CASE_COLUMNS`."""
    rows = [[col.cell(c.row()) for col in CASE_COLUMNS] for c in cases]
    headers = [c.header for c in CASE_COLUMNS]
    wrap = [h == "outcome" for h in headers]
    return table(headers, rows, [c.numeric for c in CASE_COLUMNS], wrap)


def image(name: str, data: bytes, dpi: float, alt: str, caption: str) -> str:
    """A PNG figure as an ``<img>`` with ``alt`` text, its size, and a caption."""
    width, height = struct.unpack(">II", data[16:24])  # the PNG's IHDR chunk
    scale = DISPLAY_PX_PER_INCH / dpi
    src = "data:image/png;base64," + base64.b64encode(data).decode("ascii")
    return (
        f"<figure id='{html.escape(name.rsplit('.', 1)[0])}'>"
        f"<img src='{src}' alt='{html.escape(alt, quote=True)}' "
        f"width='{round(width * scale)}' height='{round(height * scale)}'>"
        f"<figcaption>{html.escape(caption)}</figcaption></figure>"
    )


def report_page(rep: Reproduction, figures: Mapping[str, bytes], dpi: float) -> str:
    """The whole page: settings, claims, the matrix and the sensitivity study with
    their figures, the fuzzy surface and the study beyond the paper.

    Parameters
    ----------
    rep : Reproduction
    figures : mapping of str to bytes
        The PNG figures by file name (``"tracking.png"``, ...).
    dpi : float
        Their resolution, dots per inch.
    """
    from .report import VOCABULARY

    def img(stem: str, caption: str) -> str:
        name = f"{stem}.png"
        return image(name, figures[name], dpi, _alt_text(rep, stem), caption)

    names = "".join(
        f"<li><b>{k}</b>: {html.escape(CONTROLLER_DESCRIPTIONS[k])}</li>" for k in CONTROLLER_KINDS
    )
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        "<meta name='viewport' content='width=device-width, initial-scale=1'>",
        f"<title>flexarm reproduce</title><style>{STYLE_SHEET}</style></head><body>",
        "<h1>Sąsiadek et al. (2014), reproduced with flexarm</h1>",
        f"<p>{html.escape(_settings_text(rep.settings))}</p>",
        "<p>Controllers, by the one name each has in this report, on the console, in the "
        f"figures and in <code>summary.json</code>:</p><ul>{names}</ul>",
        "<p>Errors are in mm, rounded to three significant figures; "
        "<code>summary.json</code> and <code>table.csv</code> hold every digit, in SI "
        "units.</p>",
        "<h2>Claims</h2>",
        f"<p>{html.escape(VOCABULARY)}</p>",
    ]
    for model in dict.fromkeys(c["sensor_model"] for c in rep.claims):
        parts.append(f"<h3>With {html.escape(MODEL_LABELS.get(model, model))}</h3><ul>")
        for c in rep.claims:
            if c["sensor_model"] != model:
                continue
            cls = {"supported": "supported", "not supported": "not"}.get(c["verdict"], "partly")
            parts.append(
                f"<li><b>{html.escape(c['claim'])}</b> — <span class='{cls}'>"
                f"{html.escape(c['verdict'])}</span>. {html.escape(c['evidence'])}</li>"
            )
        parts.append("</ul>")
    parts += [
        "<h2>The paper's matrix</h2>",
        case_table(rep.cases),
        img("tracking", "The end effector's path against the square, one panel per run."),
        img("deflections", "The tip deflection of each link, one panel per run."),
        "<h2>Sensitivity: delay models</h2>",
    ]
    if rep.delay_study:
        parts.append(
            "<p>The matrix with the paper's sensor model under each delay model: none, "
            "the seed's wave speed, the dispersive bending-wave speed (each over the path "
            "along the links to the sensor).</p>"
        )
        parts.append(case_table(rep.delay_study))
    else:
        parts.append("<p>Not run (<code>--no-sensitivity</code>).</p>")
    parts.append("<h2>Sensitivity: the fuzzy law over ks</h2>")
    if rep.ks_study:
        parts.append(case_table(rep.ks_study))
    else:
        parts.append("<p>Not run (<code>--no-sensitivity</code>).</p>")
    parts.append(img("sensitivity", "RMS error of the fuzzy law against ks, per sensor."))
    parts.append("<h2>The fuzzy adaptation</h2>")
    parts.append(img("fuzzy_surface", "The paper's fuzzy surface λ(δ1, δ2)."))
    if rep.converged is not None:
        parts.append(rep.converged.html())
    if rep.beyond is not None:
        parts.append(rep.beyond.html())
    parts.append("</body></html>\n")
    return "\n".join(parts)


def _settings_text(s: Settings) -> str:
    dur = "the full square" if s["duration_s"] is None else f"{s['duration_s']:g} s"
    return (
        f"The paper's arm (two 4.5 m links, one mode each) on the default square ({dur}), "
        f"control period {s['dt_s']:g} s. Fuzzy law: {s['law']}, ks = {s['ks']:g}. "
        f"A run tracks well when it completes and its RMS error is at most "
        f"{s['tolerance']:g} x the square's side = {sig(1e3 * s['tolerance_m'])} mm. "
        f"{s['runs']} runs in {s['wall_time_s']:.1f} s."
    )


def _diverged(cases: Sequence[CaseResult]) -> str:
    gone = [
        f"{c.case.controller} with the {SENSOR_LABELS[c.case.sensor]} sensor"
        + ("" if c.case.sensor == "joint" else f" ({c.case.sensor_model} model)")
        + f" at t = {sig(c.diverged_at_s)} s"
        for c in cases
        if c.status != "ok"
    ]
    return "Every run completed." if not gone else "Diverged: " + "; ".join(gone) + "."


def _alt_text(rep: Reproduction, stem: str) -> str:
    """What a figure shows, in words (the ``alt`` of its image)."""
    models = " and ".join(dict.fromkeys(c.case.sensor_model for c in rep.cases))
    grid = (
        f"{len(rep.cases)} panels, one per run of the paper's matrix: rows are the "
        f"controllers pd and fuzzy under the {models} sensor models, columns the joint, "
        "end-effector and 0.5 m-from-the-elbow sensors. "
    )
    if stem == "tracking":
        return (
            grid + "Each panel draws the end effector's path, y (m) against x (m), over "
            "the reference square (dashed); its title gives the RMS error or when the run "
            "diverged. " + _diverged(rep.cases)
        )
    if stem == "deflections":
        return (
            grid + "Each panel draws the tip deflection of link 1 and link 2 (mm) against "
            "time (s). " + _diverged(rep.cases)
        )
    if stem == "sensitivity":
        return (
            "Three panels, one per sensor (joint, end effector, 0.5 m from the elbow): the "
            "fuzzy law's RMS error (mm, logarithmic) against the membership-width gain ks, "
            "one marked line per sensor model and adaptation law; crosses at the top mark "
            "runs that diverged; horizontal lines are the pd runs. "
            + ("" if rep.ks_study else "No ks study was run: the panels are empty.")
        )
    return (
        "A surface of the fuzzy adaptation λ (dimensionless) over the link deflections δ1 "
        "and δ2 (m) across the paper's universe, from the paper's rule table: smallest "
        "with both links straight, largest where both are bent most."
    )
