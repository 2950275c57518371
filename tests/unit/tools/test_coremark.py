"""tools/coremark.py: EEMBC's CoreMark built with our port (tools/coremark/) and run on the model, and
the same program under QEMU (tools/coremark_qemu.py). The benchmark's sources are not in this
repository and CI cannot fetch them, nor does it install QEMU: the runs themselves are tested where a
checkout (COREMARK=DIR) and qemu-system-riscv64 are at hand, the rest always, QEMU's part with a
stand-in script for it."""
from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest

from suite import private_bench_history


from tools import coremark, coremark_qemu

# what our virt port prints under QEMU 7.2 (10,000 iterations, QEMU's clock under CoreMark's 10 s)
QEMU_REPORT = """CoreMark on QEMU virt, hart 0: mtime at 10000000 Hz
2K performance run parameters for coremark.
Total time (secs): 1.672297
ERROR! Must execute for at least 10 secs for a valid result!
seedcrc          : 0xe9f5
[0]crclist       : 0xe714
[0]crcmatrix     : 0x1fd7
[0]crcstate      : 0x8e3a
[0]crcfinal      : 0x988c
Errors detected
minstret at the end: 3928463786
"""


def test_a_folder_that_is_no_checkout_is_refused_by_name(tmp_path):
    with pytest.raises(SystemExit, match=f"{tmp_path} is not a CoreMark checkout .no core_list_join.c"):
        coremark.main([str(tmp_path), "--timing", "rocket"])


def test_bad_arguments_are_usage_errors(tmp_path, capsys):
    for args in (["--timing", "fast"], ["--iterations", "0"]):
        with pytest.raises(SystemExit) as stop:
            coremark.main([str(tmp_path), *args])
        assert stop.value.code == 2
    assert "unknown timing fast" in capsys.readouterr().err


@pytest.mark.skipif(not os.environ.get("COREMARK"), reason="no CoreMark checkout (COREMARK)")
def test_coremark_validates_and_scores_per_mhz(tmp_path, monkeypatch):
    private_bench_history(monkeypatch, tmp_path)
    assert coremark.main([os.environ["COREMARK"], "--timing", "rocket", "--out", str(tmp_path)]) == 0
    record, = json.loads((Path(tmp_path) / "coremark.json").read_text())
    assert record["validated"] and record["cpu_hz"] == 390_000_000
    assert 1.0 < record["coremark_per_mhz"] < 4.0
    qemu = json.loads((Path(tmp_path) / "qemu.json").read_text())
    assert qemu["validated"] == (shutil.which(coremark_qemu.QEMU) is not None), qemu["note"]


def fake_qemu(folder: Path, monkeypatch, run: str) -> None:
    """A stand-in qemu-system-riscv64 first on PATH: `--version` as QEMU's, any run the shell `run`."""
    script = folder / coremark_qemu.QEMU
    script.write_text(f'#!/bin/sh\n[ "$1" = --version ] && echo "QEMU emulator version 7.2.99 (stand-in)" && exit 0\n'
                      f"{run}\n")
    script.chmod(0o755)
    (folder / "report.txt").write_text(QEMU_REPORT)
    monkeypatch.setenv("PATH", f"{folder}{os.pathsep}{os.environ['PATH']}")


def test_without_qemu_the_record_says_so_and_has_no_figures(tmp_path, monkeypatch):
    monkeypatch.setattr(shutil, "which", lambda name: None)
    record = coremark_qemu.measure(tmp_path / "coremark-virt.elf", tmp_path)
    assert record["host_cpu_s"] is None and record["instructions"] is None and not record["validated"]
    assert f"{coremark_qemu.QEMU} is not installed" in record["note"] and "\n" not in record["note"]
    assert set(record) == set(coremark_qemu.FIELDS)


def test_qemu_s_run_is_timed_and_counted_and_its_crcs_are_its_verdict(tmp_path, monkeypatch):
    """CoreMark says "Errors detected" on QEMU because it ran under 10 s; its CRCs decide here."""
    fake_qemu(tmp_path, monkeypatch, f'cat "{tmp_path}/report.txt"')
    record = coremark_qemu.measure(tmp_path / "coremark-virt.elf", tmp_path / "out")
    assert record["validated"] and record["note"] is None and record["version"] == "7.2.99"
    assert record["instructions"] == 3_928_463_786 and record["coremark_s"] == pytest.approx(1.672297)
    assert record["host_cpu_s"] >= 0 and record["host_wall_s"] > 0
    assert (tmp_path / "out" / "qemu-console.log").read_text() == QEMU_REPORT


@pytest.mark.parametrize("run, note", [
    ("exec sleep 30", "QEMU's run did not finish within 0.5 s"),
    ("exit 3", "QEMU's run ended with status 3"),
    ("echo '[0]ERROR! list crc 0x1234 - should be 0xe714'; echo '[0]crcfinal : 0x1'",
     "QEMU's run did not reach CoreMark's report with its CRCs right"),
])
def test_a_qemu_run_that_hangs_fails_or_does_not_validate_is_reported_without_figures(tmp_path, monkeypatch,
                                                                                        run, note):
    fake_qemu(tmp_path, monkeypatch, run)
    record = coremark_qemu.measure(tmp_path / "coremark-virt.elf", tmp_path / "out", timeout=0.5)
    assert record["note"].startswith(note) and record["host_cpu_s"] is None and not record["validated"]
    assert record["version"] == "7.2.99"


def test_an_uncounted_qemu_run_keeps_its_time(tmp_path, monkeypatch):
    fake_qemu(tmp_path, monkeypatch, f'case "$*" in *-icount*) exit 4;; esac; cat "{tmp_path}/report.txt"')
    record = coremark_qemu.measure(tmp_path / "coremark-virt.elf", tmp_path / "out")
    assert record["validated"] and record["host_cpu_s"] is not None and record["instructions"] is None
    assert record["note"] == ("QEMU's counting run (-icount) ended with status 4 (a trap ends it with mcause + 1): "
                              "instructions not counted")


def test_make_coremark_without_qemu_records_its_figures_as_absent(tmp_path, monkeypatch, capsys):
    """No checkout or QEMU needed: the builds and the board model's runs are stood in for."""
    private_bench_history(monkeypatch, tmp_path)
    monkeypatch.setattr(shutil, "which", lambda name: None)
    monkeypatch.setattr(coremark, "build", lambda checkout, iterations, out: out / "coremark.elf")
    monkeypatch.setattr(coremark, "build_virt", lambda checkout, iterations, out: out / "coremark-virt.elf")
    monkeypatch.setattr(coremark, "run", lambda elf, timing, out: {
        "timing": timing, "validated": True, "cpu_hz": 390_000_000, "iterations_per_second": 830.8,
        "iterations": 10000.0, "instructions": 3_928_495_491, "virtual_s": 12.09, "host_wall_s": 13.5,
        "host_cpu_s": 13.2, "coremark_per_mhz": 2.13, "against_published": 1.22})
    (tmp_path / "out").mkdir()
    assert coremark.main([str(tmp_path), "--timing", "rocket", "--out", str(tmp_path / "out")]) == 0
    assert f"QEMU: {coremark_qemu.QEMU} is not installed" in capsys.readouterr().out
    line = json.loads((tmp_path / "history.jsonl").read_text())
    assert line["qemu"]["host_cpu_s"] is None and "not installed" in line["qemu"]["note"]
    assert f"Against QEMU: not measured ({coremark_qemu.QEMU} is not installed" in (tmp_path / "page.md").read_text()


@pytest.mark.skipif(not (os.environ.get("COREMARK") and shutil.which(coremark_qemu.QEMU)),
                    reason="no CoreMark checkout (COREMARK) or no qemu-system-riscv64")
def test_the_virt_build_runs_to_coremark_s_report_under_qemu_and_validates(tmp_path):
    elf = coremark.build_virt(Path(os.environ["COREMARK"]), 200, tmp_path)
    record = coremark_qemu.measure(elf, tmp_path)
    assert record["validated"], record["note"]
    assert record["note"] is None and record["instructions"] > 200 * 300_000     # ~393,000 an iteration
    assert "Iterations       : 200" in (tmp_path / "qemu-console.log").read_text()
