"""EEMBC's CoreMark on the board model (issue 31, item 3: calibration), from a checkout of
github.com/eembc/coremark (not part of this repository) with our port (tools/coremark/): built with
Debian's riscv64-unknown-elf-gcc and picolibc on the C test firmware's driver layer, run on hart 0
under each timing model, and scored as the program reports it: iterations per second of mcycle time,
and per MHz of the CPU clock. The same program (same sources, flags and iterations) is built for QEMU's
`-M virt` too, with our port there (tools/coremark/virt/), and run under qemu-system-riscv64 where it is
installed (tools/coremark_qemu.py): the board model's host CPU time against QEMU's, a figure, not a test.

    make coremark COREMARK=DIR [COREMARK_ITERATIONS=N]
    python tools/coremark.py DIR [--iterations N] [--timing rocket,rocket-nocache,ipc1] [--out DIR]

Published K210 figures to compare with (docs/measurements.md): 695.5 and 697.8 iterations per second
on a Maix board at a nominal 400 MHz, GCC 8.2, flags unknown (github.com/PaulStoffregen/CoreMark
issue 1): 1.74 CoreMark/MHz, or 1.78 at the 390 MHz the boot ROM leaves. Exit status 0 when every
run on the board model validated, 1 when one did not (CoreMark's own check of its results), 2 for bad
arguments; QEMU's run does not change it.
"""
from __future__ import annotations

import argparse
import json
import re
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))     # run as a script: the repository's packages (tools.bench_history)
PORT = ROOT / "tools" / "coremark"
VIRT_PORT = PORT / "virt"     # the port to QEMU's -M virt
CFW = ROOT / "tests" / "firmware"
CFW_BUILD = ROOT / "build" / "cfw"
SOURCES = ("core_list_join.c", "core_main.c", "core_matrix.c", "core_state.c", "core_util.c")
# the driver layer's objects CoreMark's port links with (Makefile's CFW_LIB)
LIBRARY = ("start", "sysctl", "fpioa", "gpio", "uarths", "uart", "clint", "dmac", "spi", "spi3", "lcd", "plic",
           "timer", "trap")
OPTIMISATION = "-Os"
CFLAGS = ["-march=rv64imafdc", "-mabi=lp64d", "-mcmodel=medany", OPTIMISATION, "-std=gnu11",
          "-ffunction-sections", "-fdata-sections", "--specs=picolibc.specs"]
LDFLAGS = ["-nostartfiles", "-T", str(CFW / "k210.ld"), "-Wl,--gc-sections", "-Wl,--no-relax",
           "-Wl,--no-warn-rwx-segments"]
VIRT_LDFLAGS = ["-nostartfiles", "-T", str(VIRT_PORT / "virt.ld"), "-Wl,--gc-sections", "-Wl,--no-relax",
                "-Wl,--no-warn-rwx-segments"]
TIMINGS = ("rocket", "rocket-nocache", "ipc1")
PUBLISHED_PER_MHZ = 695.5 / 400       # the lower of the published scores, at the nominal clock


def _check(checkout: Path) -> None:
    """Refuses a folder that is not a CoreMark checkout, by name."""
    missing = [name for name in (*SOURCES, "coremark.h") if not (checkout / name).is_file()]
    if missing:
        raise SystemExit(f"coremark: {checkout} is not a CoreMark checkout (no {', '.join(missing)})")


def _compile(checkout: Path, iterations: int, elf: Path, ldflags: list[str], includes: list[Path],
             port: list[Path]) -> Path:
    """CoreMark's sources with a port's files, as a performance run (2000-byte data block, seeds 0, 0,
    0x66): the same compiler, flags and iterations for every port."""
    flags = " ".join(CFLAGS)
    command = ["riscv64-unknown-elf-gcc", *CFLAGS, *ldflags, *(f"-I{path}" for path in includes),
               f"-DITERATIONS={iterations}", "-DPERFORMANCE_RUN=1", f'-DCOMPILER_FLAGS="{flags}"',
               "-o", str(elf), *(str(checkout / name) for name in SOURCES), *(str(path) for path in port), "-lm"]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise SystemExit(f"coremark: the build failed:\n{result.stderr}")
    return elf


def build(checkout: Path, iterations: int, out: Path) -> Path:
    """CoreMark for the K210 (the board model): our port on the C test firmware's driver layer."""
    _check(checkout)
    objects = [CFW_BUILD / f"{name}.o" for name in LIBRARY]
    if not all(path.exists() for path in objects):
        raise SystemExit("coremark: the C test firmware's objects are missing (make c-firmware)")
    out.mkdir(parents=True, exist_ok=True)
    return _compile(checkout, iterations, out / "coremark.elf", LDFLAGS, [PORT, CFW, checkout],
                    [PORT / "core_portme.c", *objects])


def build_virt(checkout: Path, iterations: int, out: Path) -> Path:
    """The same CoreMark for QEMU's -M virt: the virt port's start-up, linker script and core_portme.c
    with the K210 port's core_portme.h (the same configuration)."""
    _check(checkout)
    out.mkdir(parents=True, exist_ok=True)
    return _compile(checkout, iterations, out / "coremark-virt.elf", VIRT_LDFLAGS, [PORT, checkout],
                    [VIRT_PORT / "core_portme.c", VIRT_PORT / "start.S"])


def run(elf: Path, timing: str, out: Path) -> dict:
    """One run to CoreMark's score line: what it printed, and the host's time for it."""
    folder = out / timing
    started, children = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
    result = subprocess.run([sys.executable, "-m", "emulator", "run", str(elf), "--timing", timing, "--quiet",
                             "--out", str(folder), "--expect", "CoreMark 1.0 :", "--fail-on", "Errors detected",
                             "--budget", "120"], cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (children.ru_utime + children.ru_stime)
    summary = json.loads((folder / "run.json").read_text())
    lines = [entry["line"] for entry in summary["console"]]
    text = "\n".join(lines)
    def number(label: str) -> float | None:
        match = re.search(rf"{label}\s*:\s*([0-9.]+)", text)
        return float(match.group(1)) if match else None
    hz = re.search(r"CPU (\d+) Hz", text)
    per_second = number("Iterations/Sec")
    record = {
        "timing": timing, "validated": result.returncode == 0 and "Correct operation validated" in text,
        "cpu_hz": int(hz.group(1)) if hz else None, "iterations_per_second": per_second,
        "total_ticks": number("Total ticks"), "iterations": number("Iterations"),
        "instructions": sum(summary["instructions"]), "cycles": summary["cycles"][0],
        "virtual_s": summary["virtual_time_s"], "host_wall_s": wall, "host_cpu_s": cpu,
        "caches": summary.get("caches"),
    }
    if per_second and record["cpu_hz"]:
        record["coremark_per_mhz"] = per_second / (record["cpu_hz"] / 1e6)
        record["against_published"] = record["coremark_per_mhz"] / PUBLISHED_PER_MHZ
    if not record["validated"]:
        record["console"] = lines[-12:]
    return record


def qemu_summary(qemu: dict, records: list[dict]) -> str:
    """The QEMU run and each board-model run's host CPU time against it, for the terminal."""
    if qemu["host_cpu_s"] is None:
        return f"QEMU: {qemu['note']}"
    instructions = qemu["instructions"]
    rows = [f"QEMU {qemu['version']} -M virt (plain TCG): {qemu['host_cpu_s']:.2f} s host CPU, "
            f"{qemu['host_wall_s']:.2f} s wall; "
            + (f"{instructions / qemu['host_cpu_s'] / 1e6:.0f} million instructions per host CPU second "
               f"({instructions:,} counted under -icount)" if instructions else qemu["note"])
            + ("" if qemu["coremark_s"] is None else f"; {qemu['coremark_s']:.2f} s of CoreMark's own time")]
    for record in records:
        rows.append(f"  board model, {record['timing']:15} {record['host_cpu_s'] / qemu['host_cpu_s']:.2f} x "
                    "QEMU's host CPU time")
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="tools/coremark.py", description=__doc__.splitlines()[0])
    parser.add_argument("checkout", help="a checkout of github.com/eembc/coremark")
    parser.add_argument("--iterations", type=int, default=10_000,
                        help="CoreMark's own rule: at least 10 s of its time (about 8,500 here)")
    parser.add_argument("--timing", default=",".join(TIMINGS), help="comma-separated timing models")
    parser.add_argument("--out", default=str(ROOT / "build" / "coremark"))
    args = parser.parse_args(argv)
    timings = [name.strip() for name in args.timing.split(",") if name.strip()]
    unknown = [name for name in timings if name not in TIMINGS]
    if unknown or args.iterations < 1:
        parser.error(f"unknown timing {', '.join(unknown)}" if unknown else "--iterations must be at least 1")
    out = Path(args.out)
    elf = build(Path(args.checkout), args.iterations, out)
    virt_elf = build_virt(Path(args.checkout), args.iterations, out)
    records = [run(elf, timing, out) for timing in timings]
    (out / "coremark.json").write_text(json.dumps(records, indent=2) + "\n")
    from tools import coremark_qemu
    qemu = coremark_qemu.measure(virt_elf, out)
    (out / "qemu.json").write_text(json.dumps(qemu, indent=2) + "\n")
    print(f"CoreMark, {args.iterations} iterations, {OPTIMISATION}; published K210: {PUBLISHED_PER_MHZ:.2f} "
          f"CoreMark/MHz (695.5 iterations/s at 400 MHz)")
    for record in records:
        score = record.get("coremark_per_mhz")
        print(f"  {record['timing']:15} {'validated' if record['validated'] else 'NOT VALIDATED':13} "
              f"{record['iterations_per_second'] or 0:9.1f} iterations/s at {(record['cpu_hz'] or 0) / 1e6:.0f} MHz: "
              f"{score or 0:.3f} CoreMark/MHz ({record.get('against_published', 0):.2f} x published); "
              f"{record['instructions'] / max(record['host_cpu_s'], 1e-9) / 1e6:.0f} million instructions per host "
              f"CPU second, real-time factor {record['virtual_s'] / max(record['host_cpu_s'], 1e-9):.2f} (CPU time), "
              f"{record['virtual_s'] / max(record['host_wall_s'], 1e-9):.2f} (wall)")
    print(qemu_summary(qemu, records))
    print(f"written to {out / 'coremark.json'} and {out / 'qemu.json'}")
    if all(record["validated"] for record in records):
        from tools import bench_history
        bench_history.append(None, coremark=[{key: record.get(key) for key in bench_history.COREMARK_FIELDS}
                                             for record in records],
                             qemu={key: qemu.get(key) for key in bench_history.QEMU_FIELDS})
        print(f"recorded in {bench_history.HISTORY}; the table in "
              f"{bench_history.PAGE}")
    return 0 if all(record["validated"] for record in records) else 1


if __name__ == "__main__":
    sys.exit(main())
