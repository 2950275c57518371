"""make bench's record (tools/bench_history.py): a line of JSON a run in docs/bench-history.jsonl, and
docs/measurements.md's tables and the README's calibration table generated from the latest lines."""
from __future__ import annotations

import json

import pytest

from tools import bench_history


@pytest.fixture
def private(tmp_path, monkeypatch):
    """A history, a page and a README of the test's own: (history, page, readme)."""
    history, page, readme = tmp_path / "history.jsonl", tmp_path / "page.md", tmp_path / "README.md"
    page.write_text(f"# page\n\n{bench_history.BEGIN}\nold\n{bench_history.END}\n\nafter\n")
    readme.write_text(f"# readme\n\n{bench_history.CALIBRATION_BEGIN}\n{bench_history.CALIBRATION_END}\n")
    history.write_text("")
    monkeypatch.setattr(bench_history, "HISTORY", history)
    monkeypatch.setattr(bench_history, "PAGE", page)
    monkeypatch.setattr(bench_history, "README", readme)
    return history, page, readme


def test_the_pages_table_is_the_latest_runs(capsys):
    assert bench_history.main(["--check"]) == 0, capsys.readouterr().out


def test_a_run_is_appended_and_the_table_follows_it(private, capsys):
    history, page, _ = private
    results = {"firmware": {"real_time_factor": 1.25, "host_ms_per_frame": 6.1}, "raw_unicorn_mips": 2600.0,
               "output_memory": {"10000": {"rss_after_mb": 69.4}}}
    line = bench_history.append(results)
    assert json.loads(history.read_text().splitlines()[-1]) == line
    assert line["figures"]["real-time factor after loading (virtual s per host s)"] == 1.25
    assert line["figures"]["SPI0 fed by the CPU, host CPU per FIFO store"] is None     # not measured
    text = page.read_text()
    assert "| real-time factor after loading (virtual s per host s) | 1.250 |  |" in text
    assert "| run output, resident memory after 10,000 frames | 69 | MB |" in text
    assert "| SPI0 fed by the CPU, host CPU per FIFO store | - | us |" in text
    assert text.startswith("# page\n") and text.endswith("\n\nafter\n") and "old" not in text
    assert bench_history.main(["--check"]) == 0
    bench_history.append({"firmware": {"real_time_factor": 0.9}})       # a later run: the table is its
    assert "| 0.900 |" in page.read_text() and len(history.read_text().splitlines()) == 2
    page.write_text(page.read_text().replace("0.900", "9.999"))
    assert bench_history.main(["--check"]) == 1 and "not the latest run's" in capsys.readouterr().out


def test_the_host_cost_of_a_cpu_fed_spi_fifo_is_stated():
    """Issue 32, item 9: feeding SPI0 from the CPU costs tens of microseconds of host time a store,
    and nothing said so. The latest bench run's figure is in the page's table, and the page says what
    it means against DMA, where a firmware engineer reads (docs/guide/your-own-firmware.md)."""
    label = "SPI0 fed by the CPU, host CPU per FIFO store"
    figure = bench_history.latest()["figures"][label]
    assert figure is not None and figure > 0
    assert f"| {label} | {figure:.1f} | us |" in bench_history.PAGE.read_text()
    guide = (bench_history.ROOT / "docs" / "guide" / "your-own-firmware.md").read_text()
    assert "feeds an SPI FIFO from the CPU" in guide and "DMA" in guide


def test_the_thesis_and_the_settings_tables_come_from_their_latest_runs(private):
    """The page's other tables are data too (issue 32: no narrated runs): the thesis's spans beside the
    speed run's, and each precision setting's cost and PSNR from the latest full sweep, even when a
    later run measured speed only."""
    history, page, _ = private

    def sweep(setting, mode, scene, cycles, ideal):
        return {"scene": scene, "scale": 0.9, "mode": mode, "setting": setting, "instructions_hart0": cycles // 2,
                "cycles_hart0": cycles, "psnr_db": 50.0, "psnr_ideal_db": ideal, "host_time_s": 1.0}
    settings = [sweep("default", "textured", "torus", 1000, 42.7), sweep("default", "textured", "cube", 2000, 35.8),
                sweep("affine", "textured", "torus", 700, 42.6), sweep("affine", "textured", "cube", 1800, None),
                sweep("default", "wireframe", "torus", 100, 33.9)]
    line = bench_history.append({"sd": {"texture_read_ms": 60.2, "reset_to_first_frame_ms": 144.1}}, settings)
    assert "host_time_s" not in line["settings"][0]
    bench_history.append({"firmware": {"real_time_factor": 1.5}, "sd": {"texture_read_ms": 50.0}})  # speed only
    text = page.read_text()
    assert "| SD: 183.2 KiB texture | 200.75 ms | 50.00 ms | 0.25 |" in text       # the latest speed run's
    assert "| start-up to the main loop, model A's files | 344.3 ms | - | - |" in text
    assert "(torus / cube)" in text
    assert "| affine | 0.70-0.90 | 42.6 / exact |" in text                          # the sweep's, one run back
    assert "| default | 1.00 | 42.7 / 35.8 |" in text and "wireframe:" in text and "| default | 1.00 | 33.9 / - |" in text
    assert bench_history.main(["--check"]) == 0


def test_the_settings_table_adds_the_square_texel_ideal_where_the_sweep_has_it(private):
    history, page, _ = private
    settings = [{"scene": scene, "scale": 0.9, "mode": "textured", "setting": "default", "instructions_hart0": 1,
                 "cycles_hart0": 2, "psnr_db": 50.0, "psnr_ideal_db": ideal, "psnr_square_db": square}
                for scene, ideal, square in (("torus", 44.4, 42.7), ("cube", 45.0, 31.0))]
    bench_history.append(None, settings)
    text = page.read_text()
    assert "| setting | cycles (x default) | dB vs ideal | dB vs square-texel ideal |" in text
    assert "| default | 1.00 | 44.4 / 45.0 | 42.7 / 31.0 |" in text
    assert bench_history.main(["--check"]) == 0


def test_the_settings_table_counts_both_harts_cycles_where_the_sweep_kept_hart_1_s(private):
    """A setting that sets hart 1 drawing (harts = auto) costs both harts' cycles: here hart 0's own
    fall to 0.8 of the default's while the frame costs 1.6 times as much."""
    history, page, _ = private
    settings = [{"scene": "monkey", "scale": 0.9, "mode": "flat", "setting": setting, "instructions_hart0": 1,
                 "cycles_hart0": hart0, "cycles_hart1": hart1, "psnr_db": 50.0, "psnr_ideal_db": 47.0}
                for setting, hart0, hart1 in (("default", 1000, 0), ("phong", 800, 800))]
    line = bench_history.append(None, settings)
    assert line["settings"][1]["cycles_hart1"] == 800
    text = page.read_text()
    assert "both harts' cycles a frame as a multiple of the default's" in text
    assert "| phong | 1.60 | 47.0 |" in text
    assert bench_history.main(["--check"]) == 0


def test_the_coremark_table_comes_from_the_latest_coremark_run(private):
    history, page, _ = private
    run = {"timing": "rocket", "cpu_hz": 390_000_000, "iterations": 10000, "iterations_per_second": 832.0,
           "coremark_per_mhz": 2.1333, "instructions": 3_000_000_000, "virtual_s": 12.0, "host_wall_s": 10.0}
    bench_history.append(None, coremark=[run])
    bench_history.append({"firmware": {"real_time_factor": 1.5}})     # a later speed run keeps it
    text = page.read_text()
    assert "| rocket | 2.133 | 1.19-1.23 | 832.0 | 300 million | 1.20 |" in text
    assert "QEMU" not in text                                         # a line from before QEMU's figure


def test_the_coremark_table_sets_the_board_model_s_host_time_against_qemu_s(private):
    """Issue 31, item 4: the ratio to QEMU on the same CoreMark, per timing, with instructions per host
    CPU second for both; QEMU's count where it counted them, else the board model's, said to be so."""
    history, page, _ = private
    runs = [{"timing": "rocket", "cpu_hz": 390_000_000, "iterations": 10000, "iterations_per_second": 830.8,
             "coremark_per_mhz": 2.13, "instructions": 3_900_000_000, "virtual_s": 12.0, "host_wall_s": 13.5,
             "host_cpu_s": 13.0},
            {"timing": "ipc1", "cpu_hz": 390_000_000, "iterations": 10000, "iterations_per_second": 992.8,
             "coremark_per_mhz": 2.55, "instructions": 3_900_000_000, "virtual_s": 10.0, "host_wall_s": 8.5,
             "host_cpu_s": 0.5}]
    qemu = {"version": "7.2.22", "validated": True, "coremark_s": 1.67, "instructions": 4_000_000_000,
            "host_cpu_s": 1.6, "host_wall_s": 1.9, "note": None}
    line = bench_history.append(None, coremark=runs, qemu={**qemu, "extra": 1})
    assert line["qemu"] == qemu
    text = page.read_text()
    assert "| QEMU 7.2.22 -M virt | 1.60 | 1.90 | 2500 million | 1 |" in text
    assert "| board model, rocket | 13.00 | 13.50 | 300 million | 8.1 x slower |" in text
    assert "| board model, ipc1 | 0.50 | 8.50 | 7800 million | 3.2 x faster |" in text
    assert "counted under `-icount`" in text and "(1.67 s of QEMU's clock, under CoreMark's 10 s rule)" in text
    assert bench_history.main(["--check"]) == 0

    bench_history.append(None, coremark=runs, qemu={**qemu, "instructions": None, "coremark_s": 12.0})
    text = page.read_text()
    assert "| QEMU 7.2.22 -M virt | 1.60 | 1.90 | 2438 million | 1 |" in text     # the board model's count
    assert "taken as the board model's count (approximate" in text and "CoreMark validated QEMU's run" in text

    note = "qemu-system-riscv64 is not installed (apt-get install qemu-system-misc): no QEMU figures"
    bench_history.append(None, coremark=runs, qemu={**{key: None for key in bench_history.QEMU_FIELDS}, "note": note})
    text = page.read_text()
    assert f"Against QEMU: not measured ({note})." in text and "| QEMU" not in text
    assert "| rocket | 2.130 |" in text


def test_the_thesis_firmware_table_comes_from_its_latest_run(private):
    history, page, _ = private
    runs = [{"model": "A", "thesis_ms": 344.3, "timing": "rocket", "start_up_ms": 254.37},
            {"model": "A", "thesis_ms": 344.3, "timing": "ipc1", "start_up_ms": 231.84}]
    bench_history.append(None, thesis_firmware=runs)
    assert "| model A: start-up to its main loop | 344.3 ms | 254.4 ms (0.74) | 231.8 ms (0.67) |" in page.read_text()


def test_the_readme_s_calibration_table_sets_the_default_model_against_the_chip(private, capsys):
    """Issue 31: the calibration table in the README, each span the chip was measured on with its
    source, from the latest CoreMark and thesis-firmware runs under the default timing."""
    _, _, readme = private
    coremark = [{"timing": "rocket", "cpu_hz": 390_000_000, "iterations": 10000, "iterations_per_second": 832.0,
                 "coremark_per_mhz": 2.1333, "instructions": 3_000_000_000, "virtual_s": 12.0, "host_wall_s": 10.0},
                {"timing": "ipc1", "coremark_per_mhz": 2.5, "cpu_hz": 1, "iterations": 1, "instructions": 1,
                 "virtual_s": 1.0, "host_wall_s": 1.0}]
    thesis = [{"model": "A", "thesis_ms": 344.3, "timing": "rocket", "start_up_ms": 347.6,
               "thesis_sd_phases_ms": {"set_up": 32.35, "texture": 200.75}, "sd_phases_ms": {"set_up": 28.04,
                                                                                          "texture": 205.17}},
              {"model": "C", "thesis_ms": 87.8, "timing": "rocket", "start_up_ms": 88.5, "thesis_sd_phases_ms": {}},
              {"model": "C", "thesis_ms": 87.8, "timing": "ipc1", "start_up_ms": 68.1}]
    bench_history.append(None, coremark=coremark)
    bench_history.append(None, thesis_firmware=thesis)
    text = readme.read_text()
    assert "| CoreMark/MHz | 1.74-1.79 | 2.133 | 1.19-1.23 | github.com/PaulStoffregen/CoreMark issue 1 (GCC 8.2) |" in text
    assert "| thesis firmware, model A: start-up to its main loop | 344.3 ms | 347.6 ms | 1.01 |" in text
    assert "| thesis firmware, model A: SD card set-up to the root directory | 32.35 ms | 28.0 ms | 0.87 |" in text
    assert "| thesis firmware, model A: SD texture read | 200.75 ms | 205.2 ms | 1.02 |" in text
    assert "| thesis firmware, model C: start-up to its main loop | 87.8 ms | 88.5 ms | 1.01 |" in text
    assert "68.1" not in text                                   # the default timing's runs only
    assert text.startswith("# readme\n") and bench_history.main(["--check"]) == 0
    readme.write_text(text.replace("347.6", "300.0"))
    assert bench_history.main(["--check"]) == 1 and "README.md" in capsys.readouterr().out
