"""CoreMark under QEMU (issue 31, item 4): the board model's host time for CoreMark set beside QEMU's
for the same program. tools/coremark.py builds the same sources with the same flags and iterations for
QEMU's `-M virt` machine with our port (tools/coremark/virt/); this module runs that build under
qemu-system-riscv64 (Debian's qemu-system-misc) with plain TCG and times it in host CPU seconds, then
runs it once more under `-icount shift=0,sleep=off`, where QEMU's minstret counts the instructions
retired, to count them exactly (that run is slower and not timed). A figure to state, not a test:
without QEMU, or when a run fails or does not finish within TIMEOUT_S, the record's figures are None
and its note says why.

CoreMark's own verdict on QEMU's run is "Errors detected" whenever QEMU runs the iterations in under
10 s of its clock (CoreMark's rule for a reportable score), which a fast host does: `validated` here
is CoreMark's check of its results (its list, matrix and state CRCs against the performance run's),
and `coremark_s` the seconds CoreMark measured.
"""
from __future__ import annotations

import re
import resource
import shutil
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

QEMU = "qemu-system-riscv64"
INSTALL = "apt-get install qemu-system-misc"
# one hart, no firmware (QEMU's reset vector jumps to the ELF at 0x8000_0000), the UART on stdout
MACHINE = ("-M", "virt", "-bios", "none", "-nographic")
# one instruction a nanosecond of QEMU's clock, so that minstret counts them; sleep=off keeps the clock from
# running on while the hart waits to start (with it on, counts differed by up to 10^5 from run to run)
COUNTING = ("-icount", "shift=0,sleep=off")
TIMEOUT_S = 600.0                        # generous: QEMU runs 10,000 iterations in seconds
# a record's fields
FIELDS = ("version", "validated", "coremark_s", "instructions", "host_cpu_s", "host_wall_s", "note")
REPORT_END = "[0]crcfinal"               # CoreMark's report's last result line
CRC_ERROR = re.compile(r"ERROR! (list|matrix|state) crc|Cannot validate operation")
MINSTRET = re.compile(r"minstret at the end: (\d+)")


@dataclass
class Run:
    """One QEMU run: its console, exit status (None when it did not finish) and host times."""
    console: str
    status: int | None
    host_wall_s: float
    host_cpu_s: float


def absent(note: str, version: str | None = None) -> dict:
    """A record with no figures, and why."""
    record: dict = {key: None for key in FIELDS}
    record.update(version=version, validated=False, note=note)
    return record


def version(executable: str) -> str | None:
    """QEMU's version number ("7.2.22"), from `--version`'s first line."""
    try:
        first = subprocess.run([executable, "--version"], capture_output=True, text=True, timeout=30).stdout
    except (OSError, subprocess.TimeoutExpired):
        return None
    match = re.search(r"version (\S+)", first)
    return match.group(1) if match else None


def run(executable: str, elf: Path, counting: bool, timeout: float) -> Run:
    """QEMU on `elf` until the program ends it through virt's test device, or `timeout` seconds.
    Host CPU time is every thread's of the QEMU process (TCG's, the I/O thread's), as the kernel
    accounts a waited-for child; a run cut off at the timeout is killed and waited for."""
    command = [executable, *MACHINE, *(COUNTING if counting else ()), "-kernel", str(elf)]
    started, before = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        result = subprocess.run(command, stdin=subprocess.DEVNULL, capture_output=True, timeout=timeout)
        console, status = result.stdout.decode(errors="replace"), result.returncode
    except subprocess.TimeoutExpired as stop:
        console, status = (stop.stdout or b"").decode(errors="replace"), None
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    return Run(console, status, wall, cpu)


def validated(console: str) -> bool:
    """CoreMark reached its report's end and found its CRCs right (its 10 s rule aside)."""
    return REPORT_END in console and not CRC_ERROR.search(console)


def _failure(what: str, result: Run, timeout: float) -> str | None:
    if result.status is None:
        return f"QEMU's {what} did not finish within {timeout:g} s"
    if result.status != 0:
        return f"QEMU's {what} ended with status {result.status} (a trap ends it with mcause + 1)"
    if not validated(result.console):
        return f"QEMU's {what} did not reach CoreMark's report with its CRCs right"
    return None


def measure(elf: Path, out: Path, timeout: float = TIMEOUT_S) -> dict:
    """The QEMU record for the virt build `elf` (FIELDS); each run's console in `out`."""
    executable = shutil.which(QEMU)
    if executable is None:
        return absent(f"{QEMU} is not installed ({INSTALL}): no QEMU figures")
    found = version(executable)
    out.mkdir(parents=True, exist_ok=True)
    timed = run(executable, elf, counting=False, timeout=timeout)
    (out / "qemu-console.log").write_text(timed.console)
    failure = _failure("run", timed, timeout)
    if failure:
        return absent(failure, found)
    seconds = re.search(r"Total time \(secs\)\s*:\s*([0-9.]+)", timed.console)
    record = {"version": found, "validated": True, "coremark_s": float(seconds.group(1)) if seconds else None,
              "instructions": None, "host_cpu_s": timed.host_cpu_s, "host_wall_s": timed.host_wall_s, "note": None}
    counted = run(executable, elf, counting=True, timeout=timeout)
    (out / "qemu-icount-console.log").write_text(counted.console)
    retired = MINSTRET.search(counted.console)
    failure = _failure("counting run (-icount)", counted, timeout)
    if failure or not retired:
        record["note"] = (failure or "QEMU's counting run printed no minstret") + ": instructions not counted"
    else:
        record["instructions"] = int(retired.group(1))
    return record
