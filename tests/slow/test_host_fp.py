"""The fast engine's floating point on other hosts (emulator/cpu/_host_fp.h, _fast_engine.c): it
builds with C99's <fenv.h> only (no x86 intrinsics), and a host that detects tininess before
rounding, unlike RISC-V, is recognised so that the operations that round hand over to the precise
engine there. Checked natively, and for AArch64 with Debian's cross compiler and qemu-user (both
installed by tools/ensure-toolchain.sh)."""
from __future__ import annotations

import platform
import shutil
import subprocess
from pathlib import Path

import pytest

from suite import ROOT

CPU = ROOT / "emulator" / "cpu"
PROBE = '#include <stdio.h>\n#include "_host_fp.h"\nint main(void) { printf("%d", host_tiny_before_rounding()); return 0; }\n'
# setup.py's flags for the fast engine, and -Werror
FLAGS = ["-std=gnu11", "-O2", "-ffp-contract=off", "-fno-fast-math", "-fvisibility=hidden", "-fPIC", "-Wall", "-Wextra",
         "-Werror"]
CROSS = "aarch64-linux-gnu-gcc"


def probe(tmp_path: Path, cc: str, runner: list[str], static: bool = False) -> str:
    (tmp_path / "probe.c").write_text(PROBE)
    exe = tmp_path / "probe"
    subprocess.run([cc, *FLAGS, *(["-static"] if static else []), f"-I{CPU}", str(tmp_path / "probe.c"), "-o", str(exe),
                    "-lm"], check=True, capture_output=True, text=True)
    return subprocess.run([*runner, str(exe)], check=True, capture_output=True, text=True).stdout


def test_this_host_s_tininess_is_recognised(tmp_path):
    expected = {"x86_64": "0", "aarch64": "1"}.get(platform.machine())
    if expected is None:
        pytest.skip(f"no known answer for {platform.machine()}")
    assert probe(tmp_path, "gcc", []) == expected


@pytest.mark.skipif(not (shutil.which(CROSS) and shutil.which("qemu-aarch64")), reason="no AArch64 cross compiler or qemu-user")
def test_an_aarch64_host_is_recognised(tmp_path):
    assert probe(tmp_path, CROSS, ["qemu-aarch64"], static=True) == "1"


@pytest.mark.skipif(not shutil.which(CROSS), reason="no AArch64 cross compiler")
def test_the_fast_engine_builds_for_aarch64(tmp_path):
    for source in ("_fast_engine.c",):
        result = subprocess.run([CROSS, *FLAGS, "-c", str(CPU / source), "-o", str(tmp_path / "fe.o")],
                                capture_output=True, text=True)
        assert result.returncode == 0, result.stderr
    assert "xmmintrin" not in (CPU / "_fast_engine.c").read_text()
