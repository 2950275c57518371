"""The bench's precision sweep: settings, Pareto front, table writers and plot (tools/quality.py),
and which runs tools/bench.py plans. Pure functions on made-up records: no emulator runs."""
from __future__ import annotations

import csv
import io
import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from tools import quality
from tools.quality import pareto_front

SVG = "{http://www.w3.org/2000/svg}"


def rec(setting: str, instructions: float, psnr: float, *, scene: str = "A torus", mode: str = "textured",
        scale: float = 0.35, max_error: int = 10, pixels_differ: float = 0.01) -> dict:
    return {"scene": scene, "scale": scale, "mode": mode, "setting": setting, "instructions_hart0": instructions,
            "psnr_db": psnr, "max_error": max_error, "pixels_differ": pixels_differ}


# --- settings -------------------------------------------------------------------------------------

def test_settings_are_ordered_default_first_and_use_known_keys_and_values():
    names = list(quality.SETTINGS)
    assert names[0] == quality.DEFAULT_SETTING == "default" and quality.SETTINGS["default"] == {}
    assert names == ["default", "affine", "gouraud", "phong", "light-33", "light-9", "angle-table", "depth-float32",
                     "pixel-snap", "bilinear", "mipmap", "edge-aa", "supersample", "thesis", "best", "most-accurate"]
    for name, keys in quality.SETTINGS.items():
        for key, value in keys.items():
            assert value in quality.PRECISION_KEYS[key], (name, key, value)
    assert quality.SETTINGS["most-accurate"] == {"antialias": "supersample", "depth": "float32",
                                                 "light_levels": "65537", "shading": "phong",
                                                 "filter": "anisotropic"}
    assert quality.SETTINGS["thesis"] == {"interpolation": "affine", "shading": "flat", "light_levels": "33",
                                          "angles": "table", "depth": "int16", "snap": "pixel"}
    # the single-knob settings differ from the default in exactly one key, and not in its default value
    for name in names[1:12]:
        (key, value), = quality.SETTINGS[name].items()
        assert value != quality.PRECISION_KEYS[key][0]


def test_wireframe_sweeps_only_the_settings_that_change_it():
    assert quality.settings_for_mode("wireframe") == ["default", "angle-table", "pixel-snap", "edge-aa",
                                                      "supersample"]
    # texture filtering only in textured mode
    assert quality.settings_for_mode("textured") == list(quality.SETTINGS)
    assert quality.settings_for_mode("flat") == [n for n in quality.SETTINGS if n not in ("bilinear", "mipmap")]
    assert quality.settings_for_mode("textured", ["best", "default", "nonsense"]) == ["default", "best"]
    assert quality.settings_for_mode("wireframe", ["affine"]) == []


# --- the Pareto front -----------------------------------------------------------------------------

def test_dominated_point_is_off_the_front():
    records = [rec("default", 100, 40), rec("cheap", 80, 35), rec("worse", 120, 38), rec("best", 150, 45)]
    assert pareto_front(records) == {"default", "cheap", "best"}
    assert quality.dominated_by(records, "worse") == ["default"]


def test_equal_cost_lower_psnr_and_equal_psnr_higher_cost_are_dominated():
    records = [rec("a", 100, 40), rec("same-cost-worse", 100, 39.9), rec("same-psnr-dearer", 101, 40)]
    assert pareto_front(records) == {"a"}


def test_ties_are_both_on_the_front():
    records = [rec("default", 100, 40), rec("affine", 100, 40), rec("dear", 200, 41)]
    assert pareto_front(records) == {"default", "affine", "dear"}


def test_infinite_psnr_beats_every_finite_and_ties_with_itself():
    records = [rec("exact", 200, math.inf), rec("also-exact", 200, math.inf), rec("dearer-exact", 300, math.inf),
               rec("good", 250, 99.0), rec("cheap", 100, 30)]
    assert pareto_front(records) == {"exact", "also-exact", "cheap"}


def test_single_record_and_empty():
    assert pareto_front([rec("default", 1, 1)]) == {"default"}
    assert pareto_front([]) == set()


def test_front_report_says_whether_default_is_on_the_front_per_panel():
    records = [rec("default", 100, 40), rec("fast", 90, 41),
               rec("default", 100, 40, mode="flat"), rec("fast", 90, 39, mode="flat"),
               rec("fast", 90, 39, mode="wireframe")]
    lines = quality.front_report(records)
    assert lines == ["A torus, scale 0.35, textured: default is NOT on the Pareto front (dominated by fast)",
                     "A torus, scale 0.35, flat: default is on the Pareto front",
                     "A torus, scale 0.35, wireframe: no 'default' run"]


# --- the table ------------------------------------------------------------------------------------

RECORDS = [rec("default", 200_000, 45.25, max_error=80, pixels_differ=0.0125),
           rec("affine", 150_000, 40.0), rec("gouraud", 260_000, math.inf, max_error=0, pixels_differ=0.0),
           rec("light-9", 210_000, 30.0),
           rec("default", 40_000, 32.8, mode="wireframe", scene="C cube", scale=0.9),
           rec("pixel-snap", 40_000, 32.8, mode="wireframe", scene="C cube", scale=0.9)]


def test_csv_has_one_row_per_record_with_ratio_psnr_and_front():
    rows = list(csv.DictReader(io.StringIO(quality.csv_text(RECORDS))))
    assert [r["setting"] for r in rows] == [r["setting"] for r in RECORDS]
    assert list(rows[0]) == ["scene", "scale", "mode", "setting", "instructions_per_frame", "cycles_per_frame",
                             "relative_to_default", "psnr_db", "max_error", "pixels_differ_percent", "on_front"]
    default, affine, gouraud, light9, wire_default, wire_snap = rows
    assert default["instructions_per_frame"] == "200000" and default["relative_to_default"] == "1.0000"
    assert affine["relative_to_default"] == "0.7500" and gouraud["relative_to_default"] == "1.3000"
    assert float(default["psnr_db"]) == pytest.approx(45.25) and gouraud["psnr_db"] == "inf"
    assert math.isinf(float(gouraud["psnr_db"]))
    assert float(default["pixels_differ_percent"]) == pytest.approx(1.25) and default["max_error"] == "80"
    assert [r["on_front"] for r in rows] == ["yes", "yes", "yes", "no", "yes", "yes"]
    assert wire_snap["scene"] == "C cube" and wire_snap["scale"] == "0.9" and wire_snap["relative_to_default"] == "1.0000"


def test_csv_relative_is_empty_without_a_default_run():
    rows = list(csv.DictReader(io.StringIO(quality.csv_text([rec("affine", 10, 20), rec("fast", 5, 10)]))))
    assert [r["relative_to_default"] for r in rows] == ["", ""]


def test_markdown_table():
    lines = quality.markdown_table(RECORDS).splitlines()
    assert len(lines) == 2 + len(RECORDS)
    header = [c.strip() for c in lines[0].strip("|").split("|")]
    assert header == ["scene", "scale", "mode", "setting", "instructions / frame", "cycles / frame",
                      "relative to default",
                      "PSNR (dB)", "max error", "pixels differ (%)", "on front"]
    assert all(line.count("|") == len(header) + 1 for line in lines)
    assert lines[2] == "| A torus | 0.35 | textured | **default** | 200,000 |  | 1.000 | 45.25 | 80 | 1.25 | yes |"
    assert "| gouraud | 260,000 |  | 1.300 | exact | 0 | 0.00 | yes |" in lines[4]
    assert lines[5].endswith("| no |")


def test_the_front_and_the_ratio_use_cycles_where_records_carry_them():
    """The cost of a frame is its cycles (the K210's Rocket timing): a setting with fewer
    instructions but more cycles, and a worse PSNR, is dominated."""
    records = [{**rec("default", 200_000, 45.0), "cycles_hart0": 300_000},
               {**rec("affine", 150_000, 40.0), "cycles_hart0": 320_000}]
    assert quality.pareto_front(records) == {"default"}
    rows = list(csv.DictReader(io.StringIO(quality.csv_text(records))))
    assert [r["cycles_per_frame"] for r in rows] == ["300000", "320000"]
    assert rows[1]["relative_to_default"] == f"{320 / 300:.4f}"
    assert "cycles / frame (hart 0)" in quality.svg_text(records)


def test_a_frame_costs_both_harts_cycles_where_records_carry_hart_1_s():
    """With harts = auto a setting may set hart 1 drawing: its cost is both harts' cycles, so that
    fewer of hart 0's (its share) do not make it look cheaper than the default."""
    records = [{**rec("default", 200_000, 45.0), "cycles_hart0": 300_000, "cycles_hart1": 2_000},
               {**rec("phong", 150_000, 47.0), "cycles_hart0": 240_000, "cycles_hart1": 250_000}]
    assert quality.cost(records[1]) == 490_000
    assert quality.pareto_front(records) == {"default", "phong"}
    rows = list(csv.DictReader(io.StringIO(quality.csv_text(records))))
    assert [r["cycles_per_frame"] for r in rows] == ["302000", "490000"]
    assert rows[1]["relative_to_default"] == f"{490 / 302:.4f}"
    assert "cycles / frame (both harts)" in quality.svg_text(records)


def test_write_quality_writes_the_three_files(tmp_path):
    printed = quality.write_quality(RECORDS, tmp_path / "bench")
    assert {p.name for p in (tmp_path / "bench").iterdir()} == {"quality.csv", "quality.md", "quality.svg"}
    assert quality.markdown_table(RECORDS) in (tmp_path / "bench" / "quality.md").read_text()
    assert "A torus, scale 0.35, textured: default is on the Pareto front" in printed
    assert (tmp_path / "bench" / "quality.csv").read_text() == quality.csv_text(RECORDS)


# --- the plot -------------------------------------------------------------------------------------

def points(svg: str) -> list[ET.Element]:
    root = ET.fromstring(svg)
    assert root.tag == SVG + "svg"
    return [g for g in root.iter(SVG + "g") if g.get("class") == "point"]


def test_svg_is_well_formed_with_one_point_per_record_and_a_panel_per_scene_and_mode():
    svg = quality.svg_text(RECORDS)
    root = ET.fromstring(svg)
    assert [g.get("data-setting") for g in points(svg)].count("default") == 2
    assert len(points(svg)) == len(RECORDS)
    assert len([g for g in root.iter(SVG + "g") if g.get("class") == "panel"]) == 2
    assert len([p for p in root.iter(SVG + "path") if p.get("class") == "front"]) == 2
    texts = [t.text for t in root.iter(SVG + "text")]
    assert "exact" in texts                                   # the infinite PSNR's row
    assert any("A torus, scale 0.35, textured" == t for t in texts)
    assert "instructions / frame (hart 0)" in texts and "PSNR vs reference (dB)" in texts
    assert any(t and t.endswith("k") for t in texts)          # instruction ticks


def test_svg_escapes_names_and_survives_degenerate_panels():
    odd = [rec("default", 100, math.inf, scene="<A & B>"),                      # every point exact
           rec("x", 50, 20.0, scene="solo"),                                    # one point
           rec("default", 7, 30.0, scene="same"), rec("y", 7, 30.0, scene="same"),   # coincident points
           rec("default", 1_000_000, float("nan"), scene="nan")]
    assert len(points(quality.svg_text(odd))) == len(odd)


def test_nice_ticks_cover_the_range_with_round_steps():
    ticks = quality.nice_ticks(123_456, 548_722)
    assert ticks[0] <= 123_456 and ticks[-1] >= 548_722
    steps = {round(b - a, 6) for a, b in zip(ticks, ticks[1:])}
    assert len(steps) == 1 and steps.pop() in (50_000, 100_000, 200_000)
    assert quality.nice_ticks(5, 5)[0] <= 5 <= quality.nice_ticks(5, 5)[-1]


# --- the runs the bench plans ---------------------------------------------------------------------

def test_bench_plans_each_run_once():
    pytest.importorskip("unicorn")
    from tools import bench
    runs = bench.planned_runs([bench.scene_id(model) for _, model, _, _ in bench.BENCH_SCENES], list(bench.MODES),
                              None, renderer=True, sweep=True)
    assert len(runs) == len(set(runs))
    keys = {(r[0], r[3], r[4], r[5]) for r in runs}
    # renderer table: every scale and mode, default settings
    assert all((name, scale, mode, "default") in keys
               for name, _, _, scales in bench.BENCH_SCENES for scale in scales for mode in bench.MODES)
    # sweep: first scale only; wireframe only its own settings
    per_scene = 2 * len(quality.SETTINGS) - len(quality.TEXTURE_SETTINGS) + len(quality.WIREFRAME_SETTINGS)
    second_scales = sum(len(scales) - 1 for _, _, _, scales in bench.BENCH_SCENES)
    assert len(runs) == len(bench.BENCH_SCENES) * per_scene + second_scales * len(bench.MODES)
    assert not any(mode == "wireframe" and setting == "affine" for _, _, _, _, mode, setting in runs)
    only = bench.planned_runs(["cube"], ["flat"], ["default"], renderer=False, sweep=True)
    assert only == [("C cube 6 faces, 8x8", "models/cube.obj", "textures/cube.ppm", 0.9, "flat", "default")]
    record = {"scene": "C cube 6 faces, 8x8", "scale": 0.9}
    assert bench.in_sweep(record) and not bench.in_sweep({**record, "scale": 0.45})


def test_bench_writes_every_record_and_both_tables(tmp_path):
    pytest.importorskip("unicorn")
    import json
    from tools import bench
    name = bench.BENCH_SCENES[2][0]
    extra = {"instructions_hart1": 910, "cycles_hart0": 300_000, "draw_time_ms": 0.5, "frame_time_ms": 7.6,
             "fps": 131.0}
    records = [{**rec("default", 200_000, 45.0, scene=name, scale=0.9), **extra},
               {**rec("gouraud", 220_000, math.inf, scene=name, scale=0.9), **extra},
               {**rec("default", 100_000, 44.0, scene=name, scale=0.45), **extra}]
    printed = bench.write_results(records, tmp_path, renderer=True, sweep=True)
    def no_constants(name):
        raise ValueError(f"results.json holds {name}, which strict JSON readers reject")
    written = json.loads((tmp_path / "results.json").read_text(), parse_constant=no_constants)
    assert len(written) == 3 and written[1]["psnr_db"] is None and written[0]["psnr_db"] == 45.0
    md = (tmp_path / "results.md").read_text()
    assert md.count("| C cube 6 faces, 8x8 | 0.45 |") == 1           # the second scale: renderer table only
    assert "| gouraud |" in md and "| exact |" in md
    assert bench.renderer_table(records) in md and bench.renderer_table(records) in printed
    assert quality.markdown_table(records[:2]) in md and quality.markdown_table(records[:2]) in printed
    assert len(list(csv.DictReader(io.StringIO((tmp_path / "quality.csv").read_text())))) == 2
    assert len(points((tmp_path / "quality.svg").read_text())) == 2


# --- against the ideal image too ------------------------------------------------------------------

def both(setting: str, instructions: float, psnr: float, ideal: float, **keys) -> dict:
    """A record measured against the pixel-centre image (psnr) and the ideal one (ideal)."""
    return {**rec(setting, instructions, psnr, **keys), "psnr_ideal_db": ideal, "max_error_ideal": 120,
            "pixels_differ_ideal": 0.05}


# the ideal's front differs: affine is worse than default against the pixel centres but not
# against the ideal, and gouraud equals the pixel-centre reference exactly but not the ideal
IDEAL_RECORDS = [both("default", 200_000, 45.0, 36.0), both("affine", 200_000, 40.0, 36.5),
                 both("gouraud", 260_000, math.inf, 36.2), both("dear", 300_000, 30.0, 35.0),
                 both("default", 40_000, 32.8, 25.0, mode="wireframe")]


def test_front_against_the_ideal_is_its_own():
    assert pareto_front(IDEAL_RECORDS[:4]) == {"default", "gouraud"}
    assert pareto_front(IDEAL_RECORDS[:4], quality.IDEAL) == {"affine"}
    assert quality.dominated_by(IDEAL_RECORDS[:4], "default", quality.IDEAL) == ["affine"]
    assert quality.has_ideal(IDEAL_RECORDS) and not quality.has_ideal(RECORDS)
    lines = quality.front_report(IDEAL_RECORDS)
    assert lines == ["A torus, scale 0.35, textured: default is on the Pareto front",
                     "A torus, scale 0.35, wireframe: default is on the Pareto front",
                     "A torus, scale 0.35, textured: default is NOT on the Pareto front against the ideal "
                     "(dominated by affine)",
                     "A torus, scale 0.35, wireframe: default is on the Pareto front against the ideal"]


def test_the_square_texel_ideal_gets_its_columns_front_and_panels():
    """Records measured against the square-texel ideal too (psnr_square_db): the table gains its PSNR and
    front columns, the front report and the plot a row of their own."""
    records = [{**r, "psnr_square_db": square} for r, square in zip(IDEAL_RECORDS, (40.0, 39.0, 38.0, 41.0, 30.0))]
    assert quality.has_square(records) and not quality.has_square(IDEAL_RECORDS)
    rows = list(csv.DictReader(io.StringIO(quality.csv_text(records))))
    assert list(rows[0])[-2:] == ["psnr_square_db", "on_square_front"]
    assert [r["on_square_front"] for r in rows] == ["yes", "no", "no", "yes", "yes"]
    assert rows[0]["psnr_square_db"] == "40.000"
    lines = quality.markdown_table(records).splitlines()
    header = [c.strip() for c in lines[0].strip("|").split("|")]
    assert header[-2:] == ["PSNR vs square-texel ideal (dB)", "on square-texel front"]
    assert all(line.count("|") == len(header) + 1 for line in lines)
    assert any("against the square-texel ideal" in line for line in quality.front_report(records))
    assert ", vs square-texel ideal<" in quality.svg_text(records)
    assert "square-texel" not in quality.svg_text(IDEAL_RECORDS)


def test_csv_and_markdown_carry_both_psnrs_and_both_fronts():
    rows = list(csv.DictReader(io.StringIO(quality.csv_text(IDEAL_RECORDS))))
    assert list(rows[0]) == ["scene", "scale", "mode", "setting", "instructions_per_frame", "cycles_per_frame",
                             "relative_to_default", "psnr_db", "max_error", "pixels_differ_percent", "on_front", "psnr_ideal_db",
                             "max_error_ideal", "pixels_differ_ideal_percent", "on_ideal_front"]
    assert [r["on_front"] for r in rows] == ["yes", "no", "yes", "no", "yes"]
    assert [r["on_ideal_front"] for r in rows] == ["no", "yes", "no", "no", "yes"]
    assert rows[0]["psnr_ideal_db"] == "36.000" and rows[2]["psnr_db"] == "inf"
    assert rows[0]["max_error_ideal"] == "120" and float(rows[0]["pixels_differ_ideal_percent"]) == pytest.approx(5)
    # a record without the ideal's figures among others that have them: its cells stay empty
    mixed = list(csv.DictReader(io.StringIO(quality.csv_text(IDEAL_RECORDS[:1] + [rec("old", 1, 1)]))))
    assert mixed[1]["psnr_ideal_db"] == mixed[1]["on_ideal_front"] == ""
    lines = quality.markdown_table(IDEAL_RECORDS).splitlines()
    header = [c.strip() for c in lines[0].strip("|").split("|")]
    assert header[-4:] == ["PSNR vs ideal (dB)", "max error vs ideal", "pixels differ vs ideal (%)", "on ideal front"]
    assert all(line.count("|") == len(header) + 1 for line in lines)
    assert lines[2] == ("| A torus | 0.35 | textured | **default** | 200,000 |  | 1.000 | 45.00 | 10 | 1.00 | yes | "
                        "36.00 | 120 | 5.00 | no |")
    assert "| gouraud | 260,000 |  | 1.300 | exact | 10 | 1.00 | yes | 36.20 | 120 | 5.00 | no |" in lines[4]


def test_svg_has_a_row_of_panels_against_the_ideal():
    svg = quality.svg_text(IDEAL_RECORDS)
    root = ET.fromstring(svg)
    assert len([g for g in root.iter(SVG + "g") if g.get("class") == "panel"]) == 4
    assert len([p for p in root.iter(SVG + "path") if p.get("class") == "front"]) == 4
    assert len(points(svg)) == 2 * len(IDEAL_RECORDS)
    texts = [t.text for t in root.iter(SVG + "text")]
    assert "PSNR vs ideal (dB)" in texts and "PSNR vs reference (dB)" in texts
    assert "A torus, scale 0.35, textured, vs ideal" in texts and "A torus, scale 0.35, textured" in texts
    tips = [t.text for t in root.iter(SVG + "title")]
    assert any("PSNR 36.50 dB against the ideal" in t and "on the front" in t for t in tips)
    assert any("PSNR exact dB against the pixel-centre reference" in t for t in tips)


def test_bench_writes_both_psnrs_and_the_ideal_figures(tmp_path):
    pytest.importorskip("unicorn")
    import json
    from tools import bench
    name = bench.BENCH_SCENES[2][0]
    extra = {"instructions_hart1": 910, "cycles_hart0": 300_000, "draw_time_ms": 0.5, "frame_time_ms": 7.6,
             "fps": 131.0,
             "ideal_density": 8, "ideal_seconds_per_frame": 0.4}
    records = [{**both("default", 200_000, 45.0, 36.0, scene=name, scale=0.9), **extra,
                "ideal_convergence_db": 61.25},
               {**both("gouraud", 220_000, math.inf, math.inf, scene=name, scale=0.9), **extra,
                "ideal_convergence_db": 61.25},
               {**both("default", 40_000, 30.0, 25.0, scene=name, scale=0.9, mode="wireframe"), **extra,
                "ideal_convergence_db": math.inf}]
    printed = bench.write_results(records, tmp_path, renderer=True, sweep=True)

    def no_constants(name):
        raise ValueError(f"results.json holds {name}, which strict JSON readers reject")
    written = json.loads((tmp_path / "results.json").read_text(), parse_constant=no_constants)
    assert written[0]["psnr_ideal_db"] == 36.0 and written[1]["psnr_ideal_db"] is None
    assert written[2]["ideal_convergence_db"] is None and written[0]["ideal_convergence_db"] == 61.25
    md = (tmp_path / "results.md").read_text()
    assert "| C cube 6 faces, 8x8 | 0.9 | textured | 8 | 0.40 | 61.2 |" in md
    assert "| C cube 6 faces, 8x8 | 0.9 | wireframe | 8 | 0.40 | exact |" in md
    assert "| 45.0 | 10 | 1.00 % | 36.0 |" in bench.renderer_table(records)
    assert bench.ideal_table(records) in printed
    rows = list(csv.DictReader(io.StringIO((tmp_path / "quality.csv").read_text())))
    assert [r["psnr_ideal_db"] for r in rows] == ["36.000", "inf", "25.000"]
    assert len(points((tmp_path / "quality.svg").read_text())) == 2 * 3
    assert "against its ideal image" in (tmp_path / "quality.md").read_text()


def test_bench_shares_the_reference_frames_among_precision_settings():
    pytest.importorskip("unicorn")
    from dataclasses import replace
    from reference import Mesh, Scene
    from tools import bench
    mesh = Mesh(np.zeros((3, 3)), np.zeros((0, 2)), np.zeros((0, 3)), np.zeros((1, 3, 3), np.int64))
    scene = Scene()
    key = bench._reference_key(scene, mesh, None, 6)
    precise = replace(scene, interpolation="affine", shading="gouraud", light_levels=9, angles="table",
                      depth="float32", snap="pixel", lines={"snap": 3})
    assert bench._reference_key(precise, mesh, None, 6) == key
    assert bench._reference_key(replace(scene, mode="flat"), mesh, None, 6) != key
    assert bench._reference_key(scene, mesh, np.ones((1, 1), np.uint16), 6) != key
    assert bench._reference_key(scene, mesh, None, 5) != key
    frame = np.zeros((2, 2, 3), np.uint8)
    assert bench.distance([frame], [frame]) == {"psnr_db": math.inf, "max_error": 0, "pixels_differ": 0.0}
    off = frame.copy()
    off[0, 0, 1] = 255
    assert bench.distance([off], [frame])["psnr_db"] == pytest.approx(10 * math.log10(12))


def test_the_output_memory_figure_measures_a_run_s_growth():
    """make bench's output_memory: resident memory before and after N frames of output, each count
    in a process of its own; 100 frames of noise (23 MB of pixels) leave it within a few MB."""
    from tools.bench import output_memory_figures
    figures = output_memory_figures((100,))
    figure = figures["100"]
    assert figure["rss_after_mb"] - figure["rss_before_mb"] < 8 and figure["host_s"] > 0
