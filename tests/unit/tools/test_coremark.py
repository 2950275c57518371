"""tools/coremark.py: EEMBC's CoreMark built with our port (tools/coremark/) and run on the model. The
benchmark's sources are not in this repository and CI cannot fetch them: the run itself is tested where
a checkout is at hand (COREMARK=DIR), the rest always."""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from suite import private_bench_history


from tools import coremark


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
