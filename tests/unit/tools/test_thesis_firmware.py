"""tools/thesis_firmware.py: the thesis's own firmware on the model, timed to its main loop. Its source is
not in this repository and CI cannot fetch it: the run is tested where a checkout is at hand
(THESIS=DIR), the rest always."""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from suite import private_bench_history


from tools import thesis_firmware


def test_a_folder_that_is_no_checkout_is_refused_by_name(tmp_path):
    with pytest.raises(SystemExit, match=f"{tmp_path} is not a checkout of the thesis's firmware"):
        thesis_firmware.main([str(tmp_path), "--timing", "rocket"])


def test_the_files_have_the_thesis_s_sizes():
    for model, (_, width, height, model_bytes, texture_bytes, _) in thesis_firmware.MODELS.items():
        obj, texture = thesis_firmware.files(model)
        assert len(texture) == texture_bytes and texture.startswith(b"P6\n#")
        assert texture.endswith(bytes((i * 7) & 0xFF for i in range(width * height * 3)))
        assert len(obj) == max(model_bytes, len(obj)) and obj.count(b"\nf ") > 0


@pytest.mark.skipif(not os.environ.get("THESIS"), reason="no checkout of the thesis's firmware (THESIS)")
def test_the_thesis_firmware_reaches_its_main_loop_as_on_the_dock(tmp_path, monkeypatch):
    """Issue 31's calibration bound: under the default timing the thesis's start-ups (models A, B, C)
    and model A's SD phases within 15 % of what the thesis measured on a Dock."""
    private_bench_history(monkeypatch, tmp_path)
    assert thesis_firmware.main([os.environ["THESIS"], "--timing", "rocket", "--out", str(tmp_path)]) == 0
    records = json.loads((Path(tmp_path) / "thesis-firmware.json").read_text())
    assert [r["model"] for r in records] == ["A", "B", "C"]
    assert all(0.85 <= r["start_up_ms"] / r["thesis_ms"] <= 1.15 for r in records)
    phases = records[0]["sd_phases_ms"]
    assert set(phases) == set(thesis_firmware.THESIS_SD_PHASES_MS["A"])
    assert all(0.85 <= phases[name] / dock <= 1.15 for name, dock in thesis_firmware.THESIS_SD_PHASES_MS["A"].items())
