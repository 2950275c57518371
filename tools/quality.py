"""The precision settings the bench sweeps, and what it makes of the results: which settings are
on the Pareto front of cycles per frame against PSNR, a table (CSV and Markdown) and a
plot (hand-written SVG, small multiples, one panel per scene and mode).

Pure functions over records (dicts) with no emulator in sight, so they are tested quickly
(tests/unit/tools/test_bench_quality.py). A record has at least `scene`, `scale`, `mode`, `setting`,
`instructions_hart0`, `psnr_db`, `max_error` and `pixels_differ` (a share, 0 to 1): the distance
from the reference renderer's pixel-centre image. Its cost is the CPU cycles a frame takes under the
board model's Rocket timing (emulator/cpu/timing.py): `cycles_hart0` plus `cycles_hart1` (both harts,
so that a setting that sets hart 1 drawing (`harts = auto`) is not counted at hart 0's share), hart 0's
alone in a record without hart 1's, or `instructions_hart0` in a record without cycles. A record may also carry `psnr_ideal_db`,
`max_error_ideal` and `pixels_differ_ideal`, the same against the ideal image (reference/ideal.py);
where records carry them the tables gain their columns, the front against the ideal, and the plot
a second row of panels.
"""
from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterable
from pathlib import Path
from xml.sax.saxutils import escape

from reference.scene import (ANTIALIAS_WORDS, FILTER_WORDS, LIGHT_LEVELS_DEFAULT, LIGHT_LEVELS_MAX, LIGHT_LEVELS_MIN,
                             PRECISION_WORDS)

# --- the settings ---------------------------------------------------------------------------------

# The firmware's precision keys in scene.ini and the values each takes, default first (the
# reference renderer checks them exactly as the firmware does, so its tables serve here), and
# the texture filter, which the reference's pixel-centre image follows.
PRECISION_KEYS = {**PRECISION_WORDS, "filter": FILTER_WORDS, "antialias": ANTIALIAS_WORDS,
                  "light_levels": tuple(str(n) for n in (LIGHT_LEVELS_DEFAULT,
                                                          *(n for n in range(LIGHT_LEVELS_MAX, LIGHT_LEVELS_MIN - 1, -1)
                                                            if n != LIGHT_LEVELS_DEFAULT)))}

# Every setting the bench sweeps, in the order the tables list them: name -> scene.ini keys added
# to the scene's own. "default" is the firmware as it ships; then one knob at a time; then presets.
SETTINGS: dict[str, dict[str, str]] = {
    "default":       {},
    "affine":        {"interpolation": "affine"},
    "gouraud":       {"shading": "gouraud"},
    "phong":         {"shading": "phong"},
    "light-33":      {"light_levels": "33"},
    "light-9":       {"light_levels": "9"},
    "angle-table":   {"angles": "table"},
    "depth-float32": {"depth": "float32"},
    "pixel-snap":    {"snap": "pixel"},
    "bilinear":      {"filter": "bilinear"},
    "mipmap":        {"filter": "mipmap"},
    "edge-aa":       {"antialias": "edge"},
    "supersample":   {"antialias": "supersample"},
    "thesis":        {"interpolation": "affine", "shading": "flat", "light_levels": "33", "angles": "table",
                      "depth": "int16", "snap": "pixel"},
    "best":          {"interpolation": "perspective", "shading": "gouraud", "depth": "float32"},
    # the closest to the ideal image (a camera's, textures read smooth): supersampling, depth that
    # separates the decal's two quads, light in 1/65536 steps and per pixel from the vertex normals,
    # as the ideal lights, and textures filtered along the footprint (against the square-texel ideal,
    # nearest texels would be closer where textures are magnified: the cube's 8x8 texture)
    "most-accurate": {"antialias": "supersample", "depth": "float32", "light_levels": "65537",
                      "shading": "phong", "filter": "anisotropic"},
}
DEFAULT_SETTING = "default"
# Wireframe has no texture, light or depth buffer: only the angles, the snapping and antialiased
# lines change it (edge: each line by coverage; supersample: their union, the most accurate).
WIREFRAME_SETTINGS = ("default", "angle-table", "pixel-snap", "edge-aa", "supersample")
# Texture filtering changes only what a texture draws: swept in textured mode alone.
TEXTURE_SETTINGS = ("bilinear", "mipmap")


def settings_for_mode(mode: str, wanted: Iterable[str] | None = None) -> list[str]:
    """The settings swept in this mode (in SETTINGS order), limited to `wanted` if given."""
    if mode == "wireframe":
        names = [n for n in SETTINGS if n in WIREFRAME_SETTINGS]
    elif mode == "textured":
        names = list(SETTINGS)
    else:
        names = [n for n in SETTINGS if n not in TEXTURE_SETTINGS]
    if wanted is not None:
        wanted = set(wanted)
        names = [n for n in names if n in wanted]
    return names


# --- the Pareto front -----------------------------------------------------------------------------

# What a PSNR is measured against: the record's key -> (its fields' suffix, the plot's axis label).
PIXEL_CENTRE = "psnr_db"           # the reference renderer's pixel-centre image (reference/render.py)
IDEAL = "psnr_ideal_db"            # its ideal image, a camera's (reference/ideal.py, texels smooth)
SQUARE = "psnr_square_db"          # the ideal with square texels (as nearest-texel sampling draws them)
METRICS = {PIXEL_CENTRE: ("", "PSNR vs reference (dB)"), IDEAL: ("_ideal", "PSNR vs ideal (dB)"),
           SQUARE: ("_square", "PSNR vs square-texel ideal (dB)")}


def has_ideal(records: Iterable[dict]) -> bool:
    """Whether the records carry PSNRs against the ideal image."""
    return any(r.get(IDEAL) is not None for r in records)


def has_square(records: Iterable[dict]) -> bool:
    """Whether the records carry PSNRs against the square-texel ideal."""
    return any(r.get(SQUARE) is not None for r in records)


def _quality(record: dict, metric: str = PIXEL_CENTRE) -> float:
    value = record.get(metric)
    q = math.nan if value is None else float(value)
    return -math.inf if math.isnan(q) else q


def cost(record: dict) -> float:
    """What a frame costs: both harts' cycles per frame (hart 0's in a record without hart 1's), or hart
    0's instructions in a record without cycles."""
    if record.get("cycles_hart0") is None:
        return record["instructions_hart0"]
    return record["cycles_hart0"] + (record.get("cycles_hart1") or 0)


def cost_unit(records: Iterable[dict]) -> str:
    """'cycles' when every record carries cycles, else 'instructions'."""
    return "cycles" if all(r.get("cycles_hart0") is not None for r in records) else "instructions"


def cost_label(records: list[dict]) -> str:
    """What cost counts, for an axis: its unit a frame and whose (both harts where every record has
    hart 1's cycles)."""
    whose = "both harts" if all(r.get("cycles_hart1") is not None for r in records) else "hart 0"
    return f"{cost_unit(records)} / frame ({whose})"


def dominates(a: dict, b: dict, metric: str = PIXEL_CENTRE) -> bool:
    """a is at least as cheap and at least as good as b, and strictly better in one of them."""
    ca, cb, qa, qb = cost(a), cost(b), _quality(a, metric), _quality(b, metric)
    return ca <= cb and qa >= qb and (ca < cb or qa > qb)


def pareto_front(records: Iterable[dict], metric: str = PIXEL_CENTRE) -> set[str]:
    """Names (`setting`) of the records no other record dominates, fewer cycles per frame
    and higher PSNR (`metric`: against the pixel-centre image or the ideal) being better. Equal
    points do not dominate each other: both are on the front. Infinite PSNR (frames identical to
    the reference) is better than any finite one."""
    records = list(records)
    return {r["setting"] for r in records if not any(dominates(o, r, metric) for o in records if o is not r)}


def dominated_by(records: Iterable[dict], name: str, metric: str = PIXEL_CENTRE) -> list[str]:
    """The settings that dominate the one called `name`."""
    records = list(records)
    target = [r for r in records if r["setting"] == name]
    return [o["setting"] for o in records for t in target if o is not t and dominates(o, t, metric)]


def panel_key(record: dict) -> tuple:
    return record["scene"], record["scale"], record["mode"]


def panels(records: Iterable[dict]) -> dict[tuple, list[dict]]:
    """Records grouped by (scene, scale, mode), in order of first appearance."""
    groups: dict[tuple, list[dict]] = {}
    for r in records:
        groups.setdefault(panel_key(r), []).append(r)
    return groups


def front_report(records: Iterable[dict]) -> list[str]:
    """One line per panel: is the default setting on the Pareto front? Then, where the records
    carry PSNRs against the ideal, one line per panel for the front against the ideal."""
    records = list(records)
    lines = []
    metrics = [(PIXEL_CENTRE, "the Pareto front")]
    if has_ideal(records):
        metrics.append((IDEAL, "the Pareto front against the ideal"))
    if has_square(records):
        metrics.append((SQUARE, "the Pareto front against the square-texel ideal"))
    for metric, front_name in metrics:
        for (scene, scale, mode), group in panels(records).items():
            where = f"{scene}, scale {scale:g}, {mode}"
            if not any(r["setting"] == DEFAULT_SETTING for r in group):
                lines.append(f"{where}: no '{DEFAULT_SETTING}' run")
            elif DEFAULT_SETTING in pareto_front(group, metric):
                lines.append(f"{where}: default is on {front_name}")
            else:
                lines.append(f"{where}: default is NOT on {front_name} "
                             f"(dominated by {', '.join(dominated_by(group, DEFAULT_SETTING, metric))})")
    return lines


# --- the table ------------------------------------------------------------------------------------

TABLE_COLUMNS = [  # (CSV header, Markdown header)
    ("scene", "scene"), ("scale", "scale"), ("mode", "mode"), ("setting", "setting"),
    ("instructions_per_frame", "instructions / frame"), ("cycles_per_frame", "cycles / frame"),
    ("relative_to_default", "relative to default"),
    ("psnr_db", "PSNR (dB)"), ("max_error", "max error"), ("pixels_differ_percent", "pixels differ (%)"),
    ("on_front", "on front"),
]
# and, where the records carry them, the same against the ideal image
IDEAL_COLUMNS = [
    ("psnr_ideal_db", "PSNR vs ideal (dB)"), ("max_error_ideal", "max error vs ideal"),
    ("pixels_differ_ideal_percent", "pixels differ vs ideal (%)"), ("on_ideal_front", "on ideal front"),
]
# and against the ideal with square texels, where they carry that
SQUARE_COLUMNS = [("psnr_square_db", "PSNR vs square-texel ideal (dB)"), ("on_square_front", "on square-texel front")]


def table_columns(records: Iterable[dict]) -> list[tuple[str, str]]:
    """The table's columns: TABLE_COLUMNS, IDEAL_COLUMNS where the records carry the ideal, and
    SQUARE_COLUMNS where they carry the square-texel one."""
    records = list(records)
    return (TABLE_COLUMNS + (IDEAL_COLUMNS if has_ideal(records) else [])
            + (SQUARE_COLUMNS if has_square(records) else []))


def _optional(value, kind):
    return None if value is None else kind(value)


def table_rows(records: Iterable[dict]) -> list[dict]:
    """One row per record (grouped by panel, settings in record order) with the table's columns:
    the cost (cycles, or instructions without them) relative to the same panel's default (None
    without one) and front membership,
    against the pixel-centre image and (None where a record has no ideal PSNR) the ideal."""
    rows = []
    for group in panels(records).values():
        front = pareto_front(group)
        ideal_front = pareto_front(group, IDEAL)
        square_front = pareto_front(group, SQUARE)
        default = next((r for r in group if r["setting"] == DEFAULT_SETTING), None)
        for r in group:
            ideal = r.get(IDEAL) is not None
            square = r.get(SQUARE) is not None
            rows.append({
                "scene": r["scene"], "scale": r["scale"], "mode": r["mode"], "setting": r["setting"],
                "instructions_per_frame": int(round(r["instructions_hart0"])),
                "cycles_per_frame": None if r.get("cycles_hart0") is None else int(round(cost(r))),
                "relative_to_default": (cost(r) / cost(default) if default and cost(default) else None),
                "psnr_db": float(r["psnr_db"]), "max_error": int(r["max_error"]),
                "pixels_differ_percent": 100 * float(r["pixels_differ"]),
                "on_front": r["setting"] in front,
                "psnr_ideal_db": _optional(r.get(IDEAL), float),
                "max_error_ideal": _optional(r.get("max_error_ideal"), int),
                "pixels_differ_ideal_percent": _optional(r.get("pixels_differ_ideal"), lambda v: 100 * float(v)),
                "on_ideal_front": (r["setting"] in ideal_front) if ideal else None,
                "psnr_square_db": _optional(r.get(SQUARE), float),
                "on_square_front": (r["setting"] in square_front) if square else None,
            })
    return rows


def _csv_psnr(psnr: float | None) -> str:
    return "" if psnr is None else "inf" if math.isinf(psnr) else f"{psnr:.3f}"


def _yes_no(flag: bool | None) -> str:
    return "" if flag is None else "yes" if flag else "no"


def csv_text(records: Iterable[dict]) -> str:
    """The table as CSV: plain numbers (PSNR `inf` for identical frames, relative empty without a
    default run), on_front yes/no; the ideal's columns where the records carry them (empty for a
    record without)."""
    records = list(records)
    ideal, square = has_ideal(records), has_square(records)
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow([c for c, _ in table_columns(records)])
    for row in table_rows(records):
        cells = [
            row["scene"], f"{row['scale']:g}", row["mode"], row["setting"], row["instructions_per_frame"],
            "" if row["cycles_per_frame"] is None else row["cycles_per_frame"],
            "" if row["relative_to_default"] is None else f"{row['relative_to_default']:.4f}",
            _csv_psnr(row["psnr_db"]), row["max_error"], f"{row['pixels_differ_percent']:.4f}",
            _yes_no(row["on_front"]),
        ]
        if ideal:
            cells += [_csv_psnr(row["psnr_ideal_db"]),
                      "" if row["max_error_ideal"] is None else row["max_error_ideal"],
                      "" if row["pixels_differ_ideal_percent"] is None else f"{row['pixels_differ_ideal_percent']:.4f}",
                      _yes_no(row["on_ideal_front"])]
        if square:
            cells += [_csv_psnr(row["psnr_square_db"]), _yes_no(row["on_square_front"])]
        writer.writerow(cells)
    return out.getvalue()


def _psnr_text(psnr: float | None) -> str:
    if psnr is None:
        return ""
    return "exact" if math.isinf(psnr) and psnr > 0 else f"{psnr:.2f}"


def markdown_table(records: Iterable[dict]) -> str:
    """The table in Markdown (thousands separated, PSNR `exact` for identical frames)."""
    records = list(records)
    ideal, square = has_ideal(records), has_square(records)
    lines = ["| " + " | ".join(h for _, h in table_columns(records)) + " |",
             "|" + "---|" * 3 + "---|" + "---:|" * 6 + "---|" + ("---:|" * 3 + "---|" if ideal else "")
             + ("---:|---|" if square else "")]
    for row in table_rows(records):
        relative = "" if row["relative_to_default"] is None else f"{row['relative_to_default']:.3f}"
        cycles = "" if row["cycles_per_frame"] is None else f"{row['cycles_per_frame']:,}"
        setting = f"**{row['setting']}**" if row["setting"] == DEFAULT_SETTING else row["setting"]
        line = (f"| {row['scene']} | {row['scale']:g} | {row['mode']} | {setting} | "
                f"{row['instructions_per_frame']:,} | {cycles} | {relative} | {_psnr_text(row['psnr_db'])} | "
                f"{row['max_error']} | {row['pixels_differ_percent']:.2f} | "
                f"{_yes_no(row['on_front'])} |")
        if ideal:
            differ = row["pixels_differ_ideal_percent"]
            line += (f" {_psnr_text(row['psnr_ideal_db'])} | "
                     f"{'' if row['max_error_ideal'] is None else row['max_error_ideal']} | "
                     f"{'' if differ is None else f'{differ:.2f}'} | {_yes_no(row['on_ideal_front'])} |")
        if square:
            line += f" {_psnr_text(row['psnr_square_db'])} | {_yes_no(row['on_square_front'])} |"
        lines.append(line)
    return "\n".join(lines) + "\n"


# --- the plot -------------------------------------------------------------------------------------

# Identical frames have an infinite PSNR; the plot puts them at this ceiling, on a row of its own
# labelled "exact" above a break in the axis. No finite PSNR reaches it: one channel of one pixel
# off by one in 64 frames of 320 x 240 is 119.9 dB.
PSNR_CEILING_DB = 120.0

PANEL_W, PANEL_H = 400, 290
PAD_L, PAD_R, PAD_T, PAD_B = 64, 16, 34, 46      # plot area inside a panel
EXACT_BAND = 26                                  # height of the "exact" row
EXACT_GAP = 10                                   # and the gap between it and the finite scale
FONT = "font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\""
FRONT_COLOUR, DOMINATED_COLOUR, DEFAULT_COLOUR = "#1f6fb4", "#8c8c8c", "#e8590c"


def nice_ticks(lo: float, hi: float, count: int = 5) -> list[float]:
    """Round tick values (1, 2 or 5 times a power of ten apart) covering [lo, hi]."""
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ValueError("ticks need finite bounds")
    if hi <= lo:
        hi = lo + (abs(lo) * 0.1 or 1.0)
    raw = (hi - lo) / max(1, count - 1)
    power = 10 ** math.floor(math.log10(raw))
    step = next(m * power for m in (1, 2, 5, 10) if m * power >= raw)
    first = math.floor(lo / step + 1e-9) * step
    ticks = []
    value = first
    while value < hi + step * 1e-9:
        ticks.append(round(value, 10))
        value += step
    if ticks[-1] < hi - step * 1e-9 or len(ticks) < 2:
        ticks.append(round(value, 10))
    return ticks


def _instructions_text(value: float, largest: float) -> str:
    if largest >= 10_000:
        return f"{value / 1000:g}k"
    return f"{value:g}"


def _text(x: float, y: float, body: str, size: int = 10, anchor: str = "start", extra: str = "") -> str:
    return (f'<text x="{x:.1f}" y="{y:.1f}" font-size="{size}" text-anchor="{anchor}"{extra}>'
            f"{escape(body)}</text>")


def _text_width(body: str, size: int = 10) -> float:
    return 0.58 * size * len(body)


def _overlap(a: tuple, b: tuple) -> float:
    dx = min(a[2], b[2]) - max(a[0], b[0])
    dy = min(a[3], b[3]) - max(a[1], b[1])
    return dx * dy if dx > 0 and dy > 0 else 0.0


def _place_labels(points: list[tuple[float, float, str]], bounds: tuple) -> list[tuple[float, float, str, str]]:
    """Greedy placement of one label per point (x, y, text) beside it, avoiding the other labels and
    points and staying inside bounds (x0, y0, x1, y1). Returns (x, y, anchor, text)."""
    marks = [(x - 5, y - 5, x + 5, y + 5) for x, y, _ in points]
    placed: list[tuple] = []
    out = []
    for x, y, body in sorted(points, key=lambda p: (p[1], p[0])):
        w, h = _text_width(body), 11
        candidates = [(x + 8, y + 4, "start"), (x - 8, y + 4, "end"), (x + 6, y - 8, "start"),
                      (x + 6, y + 15, "start"), (x - 6, y - 8, "end"), (x - 6, y + 15, "end")]
        best, best_cost = None, math.inf
        for tx, ty, anchor in candidates:
            box = (tx if anchor == "start" else tx - w, ty - h + 2, tx + w if anchor == "start" else tx, ty + 2)
            cost = sum(_overlap(box, other) for other in placed) + sum(_overlap(box, m) for m in marks)
            outside = (max(0, bounds[0] - box[0]) + max(0, box[2] - bounds[2]) +
                       max(0, bounds[1] - box[1]) + max(0, box[3] - bounds[3]))
            cost += outside * 50
            if cost < best_cost:
                best, best_cost = (tx, ty, anchor, box), cost
            if cost == 0:
                break
        tx, ty, anchor, box = best
        placed.append(box)
        out.append((tx, ty, anchor, body))
    return out


def _panel_svg(group: list[dict], title: str, ox: float, oy: float, metric: str = PIXEL_CENTRE) -> list[str]:
    """One panel at (ox, oy): axes, ticks, the front's step line, one point per record, labels;
    PSNR against the pixel-centre image or the ideal (`metric`)."""
    suffix, axis_label = METRICS[metric]
    left, top = ox + PAD_L, oy + PAD_T
    right, bottom = ox + PANEL_W - PAD_R, oy + PANEL_H - PAD_B
    front = pareto_front(group, metric)
    costs = [float(cost(r)) for r in group]
    exact = [r for r in group if _quality(r, metric) >= PSNR_CEILING_DB]
    finite = [_quality(r, metric) for r in group if _quality(r, metric) < PSNR_CEILING_DB and math.isfinite(_quality(r, metric))]
    # axes ranges: a little room around the points, then out to round ticks
    span = max(costs) - min(costs)
    pad = span * 0.06 if span else max(1.0, max(costs) * 0.05)
    xticks = nice_ticks(max(0.0, min(costs) - pad), max(costs) + pad)
    x0, x1 = xticks[0], xticks[-1]
    if finite:
        span = max(finite) - min(finite)
        pad = span * 0.08 if span else 1.0
        yticks = nice_ticks(min(finite) - pad, max(finite) + pad)
    else:
        yticks = []
    y_lo, y_hi = (yticks[0], yticks[-1]) if yticks else (0.0, 1.0)
    finite_top = top + EXACT_BAND + EXACT_GAP if exact else top

    def px(cost: float) -> float:
        return left + (cost - x0) / (x1 - x0) * (right - left)

    def py(psnr: float) -> float:
        if psnr >= PSNR_CEILING_DB:
            return top + EXACT_BAND / 2
        if not math.isfinite(psnr):          # -inf (NaN): at the bottom edge
            return bottom
        return bottom - (psnr - y_lo) / (y_hi - y_lo) * (bottom - finite_top)

    s = ['<g class="panel">',
         f'<rect x="{ox + 4:.1f}" y="{oy + 4:.1f}" width="{PANEL_W - 8}" height="{PANEL_H - 8}" '
         f'fill="#ffffff" stroke="#d0d0d0"/>',
         _text(ox + PANEL_W / 2, oy + 21, title, 12, "middle", ' font-weight="bold"'),
         f'<rect x="{left:.1f}" y="{top:.1f}" width="{right - left:.1f}" height="{bottom - top:.1f}" '
         f'fill="#fafafa" stroke="#444444"/>']
    for t in xticks:
        x = px(t)
        s.append(f'<line x1="{x:.1f}" y1="{top:.1f}" x2="{x:.1f}" y2="{bottom:.1f}" stroke="#e4e4e4"/>')
        s.append(f'<line x1="{x:.1f}" y1="{bottom:.1f}" x2="{x:.1f}" y2="{bottom + 4:.1f}" stroke="#444444"/>')
        s.append(_text(x, bottom + 15, _instructions_text(t, xticks[-1]), 10, "middle"))
    for t in yticks:
        y = py(t)
        s.append(f'<line x1="{left:.1f}" y1="{y:.1f}" x2="{right:.1f}" y2="{y:.1f}" stroke="#e4e4e4"/>')
        s.append(f'<line x1="{left - 4:.1f}" y1="{y:.1f}" x2="{left:.1f}" y2="{y:.1f}" stroke="#444444"/>')
        s.append(_text(left - 6, y + 3.5, f"{t:g}", 10, "end"))
    if exact:
        y = top + EXACT_BAND
        s.append(f'<line x1="{left:.1f}" y1="{y:.1f}" x2="{right:.1f}" y2="{y:.1f}" stroke="#444444" '
                 f'stroke-dasharray="4 3"/>')
        s.append(_text(left - 6, top + EXACT_BAND / 2 + 3.5, "exact", 10, "end", ' font-style="italic"'))
    s.append(_text((left + right) / 2, bottom + 32, cost_label(group), 11, "middle"))
    s.append(_text(ox + 16, (top + bottom) / 2, axis_label, 11, "middle",
                   f' transform="rotate(-90 {ox + 16:.1f} {(top + bottom) / 2:.1f})"'))
    # the front as a step line: the best PSNR available at each budget of cycles
    steps = sorted((r for r in group if r["setting"] in front), key=lambda r: (cost(r), _quality(r, metric)))
    if steps:
        d = f"M{px(cost(steps[0])):.1f},{py(_quality(steps[0], metric)):.1f}"
        for r in steps[1:]:
            d += f" H{px(cost(r)):.1f} V{py(_quality(r, metric)):.1f}"
        d += f" H{right:.1f}"
        s.append(f'<path class="front" d="{d}" fill="none" stroke="{FRONT_COLOUR}" stroke-width="2" '
                 f'stroke-opacity="0.55"/>')
    # the points, the default last so that it is drawn on top
    labels: dict[tuple[int, int], list[str]] = {}
    for r in sorted(group, key=lambda r: r["setting"] == DEFAULT_SETTING):
        x, y = px(cost(r)), py(_quality(r, metric))
        on_front = r["setting"] in front
        value = r.get(metric)
        psnr = _psnr_text(None if value is None else float(value))
        against = {IDEAL: "the ideal", SQUARE: "the square-texel ideal"}.get(metric, "the pixel-centre reference")
        differ = r.get("pixels_differ" + suffix)
        cycles = None if r.get("cycles_hart0") is None else cost(r)
        tip = (f"{r['setting']}: {int(round(r['instructions_hart0'])):,} instructions/frame"
               f"{'' if cycles is None else f', {int(round(cycles)):,} cycles/frame'}, PSNR {psnr} dB "
               f"against {against}, max error {r.get('max_error' + suffix, '?')}, "
               f"{'?' if differ is None else f'{100 * float(differ):.2f}'} % of pixels differ"
               f"{', on the front' if on_front else ''}")
        s.append(f'<g class="point" data-setting="{escape(r["setting"])}">')
        s.append(f"<title>{escape(tip)}</title>")
        if r["setting"] == DEFAULT_SETTING:
            s.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="8" fill="none" stroke="{DEFAULT_COLOUR}" '
                     f'stroke-width="2.5"/>')
        colour = FRONT_COLOUR if on_front else DOMINATED_COLOUR
        fill = colour if on_front else "#ffffff"
        s.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="4" fill="{fill}" stroke="{colour}" stroke-width="1.5"/>')
        s.append("</g>")
        labels.setdefault((round(x), round(y)), []).append(r["setting"])
    placed = _place_labels([(x, y, ", ".join(sorted(names, key=lambda n: n != DEFAULT_SETTING)))
                            for (x, y), names in labels.items()],
                           (left + 1, top + 1, right - 1, bottom - 1))
    for tx, ty, anchor, body in placed:
        weight = ' font-weight="bold"' if DEFAULT_SETTING in body.split(", ") else ""
        s.append(_text(tx, ty, body, 10, anchor, f' class="label"{weight}'))
    if any(r["setting"] == DEFAULT_SETTING for r in group):
        verdict = "default on the front" if DEFAULT_SETTING in front else "default dominated"
        s.append(_text(right - 4, bottom - 6, verdict, 9, "end",
                       f' fill="{DEFAULT_COLOUR if DEFAULT_SETTING not in front else "#555555"}"'))
    s.append("</g>")
    return s


def svg_text(records: Iterable[dict], title: str = "Cycles per frame against PSNR, per precision setting") -> str:
    """The plot: a grid of panels, one row per scene (and scale), one column per mode; where the
    records carry PSNRs against the ideal, each scene's row is followed by a row of the same
    panels against the ideal."""
    records = list(records)
    groups = panels(records)
    metrics = [PIXEL_CENTRE] + ([IDEAL] if has_ideal(records) else []) + ([SQUARE] if has_square(records) else [])
    rows = [(scene, scale, metric) for scene, scale in dict.fromkeys((scene, scale) for scene, scale, _ in groups)
            for metric in metrics]
    cols = list(dict.fromkeys(mode for _, _, mode in groups))
    header = 78
    width = max(860, max(1, len(cols)) * PANEL_W + 20)
    height = header + max(1, len(rows)) * PANEL_H + (70 if IDEAL in metrics else 52)
    s = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
         f'viewBox="0 0 {width} {height}" {FONT}>',
         f'<rect width="{width}" height="{height}" fill="#f4f4f4"/>',
         _text(width / 2, 26, title, 16, "middle", ' font-weight="bold"')]
    # the legend
    lx, ly = 20, 52
    s += [f'<circle cx="{lx + 6}" cy="{ly}" r="4" fill="{FRONT_COLOUR}" stroke="{FRONT_COLOUR}"/>',
          _text(lx + 16, ly + 4, "on the Pareto front", 11),
          f'<circle cx="{lx + 166}" cy="{ly}" r="4" fill="#ffffff" stroke="{DOMINATED_COLOUR}" stroke-width="1.5"/>',
          _text(lx + 176, ly + 4, "dominated", 11),
          f'<circle cx="{lx + 266}" cy="{ly}" r="8" fill="none" stroke="{DEFAULT_COLOUR}" stroke-width="2.5"/>',
          _text(lx + 280, ly + 4, "default setting", 11),
          f'<line x1="{lx + 390}" y1="{ly}" x2="{lx + 420}" y2="{ly}" stroke="{FRONT_COLOUR}" stroke-width="2" '
          f'stroke-opacity="0.55"/>',
          _text(lx + 426, ly + 4, "best PSNR within a budget of cycles (the front)", 11)]
    for (scene, scale, mode), group in groups.items():
        for metric in metrics:
            ox = 10 + cols.index(mode) * PANEL_W
            oy = header + rows.index((scene, scale, metric)) * PANEL_H
            title = f"{scene}, scale {scale:g}, {mode}" + {IDEAL: ", vs ideal", SQUARE: ", vs square-texel ideal"}.get(metric, "")
            s += _panel_svg(group, title, ox, oy, metric)
    s.append(_text(20, height - 32, "Fewer cycles (left) and higher PSNR against the float64 reference renderer "
                   "(up) are better; hover a point for its maximum error and share of differing pixels.", 11))
    if IDEAL in metrics:
        s.append(_text(20, height - 50, "Rows marked 'vs ideal': PSNR against the ideal image (area-averaged pixels, "
                       "area-filtered textures" + ("; read smooth, as a camera sees them, and, 'vs square-texel ideal', "
                                                   "as the squares nearest-texel sampling draws"
                                                   if SQUARE in metrics else "")
                       + "); the others against the pixel-centre image.", 11))
    s.append(_text(20, height - 14, f"Frames identical to the reference (infinite PSNR) sit on the row 'exact', "
                   f"plotted at a ceiling of {PSNR_CEILING_DB:g} dB above a break in the axis.", 11))
    s.append("</svg>")
    return "\n".join(s) + "\n"


# --- all of it ------------------------------------------------------------------------------------

def write_quality(records: list[dict], folder: Path) -> str:
    """Writes quality.csv, quality.md and quality.svg into folder; returns the Markdown report
    (the table and one line per panel on whether the default is on the front)."""
    folder.mkdir(parents=True, exist_ok=True)
    table = markdown_table(records)
    report = "\n".join(front_report(records)) + "\n"
    (folder / "quality.csv").write_text(csv_text(records))
    (folder / "quality.md").write_text(
        "# Precision settings: cycles per frame against error\n\n"
        "Per scene and mode, each precision setting's instructions and CPU cycles per frame on hart 0 (steady "
        "state; cycles as the K210's Rocket core takes them, emulator/cpu/timing.py) and "
        "how far its frames are from the float64 reference renderer: PSNR over all frames, the largest "
        "per-channel error and the share of pixels that differ. `on front`: no other setting of the same "
        "scene and mode needs no more cycles and reaches at least the PSNR, being better in one. "
        + ("The first PSNR, error and front are against the reference's pixel-centre image (its sampling is "
           "the firmware's, so they measure arithmetic); the columns `vs ideal` against its ideal image "
           "(area-averaged pixels, area-filtered textures read smooth: what a camera would see of a filtered "
           "texture, so they measure aliasing too), and `vs square-texel ideal` against the same with textures "
           "read as the squares nearest-texel sampling draws. " if has_ideal(records) else "")
        + "Plot: quality.svg.\n\n"
        "| setting | scene.ini keys |\n|---|---|\n"
        + "".join(f"| {name} | {' '.join(f'`{k} = {v}`' for k, v in keys.items()) or '(firmware defaults)'} |\n"
                  for name, keys in SETTINGS.items())
        + "\n" + table + "\n" + "".join(f"- {line}\n" for line in report.splitlines()))
    (folder / "quality.svg").write_text(svg_text(records))
    return table + "\n" + report
