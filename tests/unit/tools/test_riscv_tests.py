"""tools/riscv_tests.py: the RISC-V architectural tests on both engines. The suites themselves run
only where a checkout of riscv-tests is at hand (RISCV_TESTS, with RISCV_TESTS_ENV for its
riscv-test-env and RISCV_TESTS_SUITE early-2017 or current): CI has none, since their sources can
neither be fetched there nor vendored here. The rest checks the tool's own parts."""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from tools import riscv_tests


def test_the_makefrag_lists_are_read_across_continued_lines(tmp_path):
    (tmp_path / "Makefrag").write_text("rv64ux_sc_tests = \\\n\tadd addi \\\n\tsub \\\n\nrv64ux_p_tests = x\n")
    assert riscv_tests.makefrag_tests(tmp_path, "rv64ux") == ["add", "addi", "sub"]
    with pytest.raises(ValueError, match="rv64uy_sc_tests"):
        riscv_tests.makefrag_tests(tmp_path, "rv64uy")


@pytest.mark.parametrize("value, text", [(1, "pass"), (5, "fail 2"), (81, "fail 40"), (1337, "exception (tohost 1337)"),
                                         (1339, "exception (tohost 1339)")])
def test_tohost_is_read_as_riscv_tests_write_it(value, text):
    assert riscv_tests._decode(value) == text


def test_every_expected_outcome_says_why():
    data = json.loads(riscv_tests.EXPECTED.read_text())
    assert set(data["suites"]) == {"early-2017", "current"}
    for suite in data["suites"].values():
        assert suite["source"] and suite["measured"]
        for name, entry in suite["not passing"].items():
            assert name.split("-")[0] in riscv_tests.SUITES and "-p-" in name
            assert entry["outcome"] != "pass" and len(entry["why"]) > 20


@pytest.mark.skipif(not os.environ.get("RISCV_TESTS"), reason="no riscv-tests checkout (RISCV_TESTS)")
def test_the_suite_gives_the_expected_outcomes(tmp_path):
    checkout = Path(os.environ["RISCV_TESTS"])
    args = [str(checkout), "--out", str(tmp_path), "--suite", os.environ.get("RISCV_TESTS_SUITE", "early-2017")]
    if os.environ.get("RISCV_TESTS_ENV"):
        args += ["--env", os.environ["RISCV_TESTS_ENV"]]
    assert riscv_tests.main(args) == riscv_tests.EXIT_OK
