"""The RISC-V architectural tests (riscv-tests' isa/ suites, physical-memory "p" environment) on
the board model, on both engines: built from a checkout of their public sources with the Debian
toolchain, each run until it reports through `tohost`, the outcomes compared with
tests/data/riscv_tests_expected.json, which says for every test that does not pass why the K210 would
not pass it either.

    .venv/bin/python tools/riscv_tests.py CHECKOUT [--env ENV] [--suite early-2017|current] [--only NAME...]

CHECKOUT is a riscv-tests tree (its isa/ folder); ENV the riscv-test-env tree (default CHECKOUT/env,
the submodule). The K210's Rocket is of early 2017 (privileged spec 1.9.1), so the suite of that time
(riscv-tests a5f84ee of 2017-03-03 with riscv-test-env 9e219c9, `--suite early-2017`, the default) is
the one it would pass; today's suite (`--suite current`) checks later decisions of the ISA too
(docs/design/engines.md, "The ISA the K210 has: riscv-tests on both engines").

Exit status: 0 when every outcome is the expected one, 1 when one differs, 2 for a usage error.
"""
from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from emulator.board.dock import Board
from emulator.cpu.hart import ENGINE_FAST, ENGINE_PRECISE
from emulator.errors import BoardStop
from emulator.vtime import PS_PER_MS

ROOT = Path(__file__).resolve().parent.parent

EXPECTED = ROOT / "tests" / "data" / "riscv_tests_expected.json"
SUITES = ("rv64ui", "rv64um", "rv64ua", "rv64uf", "rv64ud", "rv64uc", "rv64mi", "rv64si")
ENGINES = (ENGINE_PRECISE, ENGINE_FAST)
CC = "riscv64-unknown-elf-gcc"
# riscv-tests' own isa/Makefile flags; the K210 is RV64GC
CFLAGS = ["-march=rv64gc_zicsr_zifencei", "-mabi=lp64", "-static", "-mcmodel=medany", "-fvisibility=hidden",
          "-nostdlib", "-nostartfiles"]
# Every test has reported by then (the longest takes under 0.2 ms at 390 MHz).
TIME_LIMIT = 2 * PS_PER_MS
EXIT_OK, EXIT_DIFFERENT, EXIT_USAGE = 0, 1, 2


@dataclass(frozen=True)
class Outcome:
    """What a test reported: "pass", "fail N" (its test case N failed: riscv-tests' RVTEST_FAIL),
    "exception N" (an exception its trap vector did not expect, during case N: the env's 1337
    marker), "no report" (tohost untouched by TIME_LIMIT) or "stop: ..." (the board stopped)."""
    text: str


def makefrag_tests(suite_dir: Path, suite: str) -> list[str]:
    """The test names a suite's Makefrag lists in `<suite>_sc_tests` (backslash-continued)."""
    text = (suite_dir / "Makefrag").read_text().replace("\\\n", " ")
    match = re.search(rf"^{suite}_sc_tests\s*=(.*)$", text, re.MULTILINE)
    if match is None:
        raise ValueError(f"{suite_dir / 'Makefrag'}: no {suite}_sc_tests list")
    return match.group(1).split()


def build(checkout: Path, env: Path, out: Path, only: set[str]) -> list[Path]:
    """Compiles every listed test of SUITES into out/<suite>-p-<test>; returns the ELFs."""
    out.mkdir(parents=True, exist_ok=True)
    elfs = []
    for suite in SUITES:
        suite_dir = checkout / "isa" / suite
        if not suite_dir.is_dir():
            continue
        for test in makefrag_tests(suite_dir, suite):
            name = f"{suite}-p-{test}"
            if only and name not in only:
                continue
            elf = out / name
            command = [CC, *CFLAGS, f"-I{env / 'p'}", f"-I{checkout / 'isa' / 'macros' / 'scalar'}",
                       f"-T{env / 'p' / 'link.ld'}", str(suite_dir / f"{test}.S"), "-o", str(elf)]
            result = subprocess.run(command, capture_output=True, text=True)
            if result.returncode != 0:
                raise RuntimeError(f"building {name} failed:\n{result.stderr}")
            elfs.append(elf)
    return elfs


def run(elf: Path, engine: str) -> Outcome:
    """Runs one test on a board (the mask ROM's hand-over state, as a kflash-loaded program
    starts) for TIME_LIMIT of virtual time, then reads what it left in tohost: a test that has
    reported spins rewriting it, so the run's end changes nothing."""
    board = Board(str(elf), engine=engine)
    tohost = board.image.symbol_values["tohost"]
    stopped = None
    try:
        board.run_until(TIME_LIMIT)
    except BoardStop as stop:
        stopped = stop
    value = int.from_bytes(board.memory.read(tohost, 8), "little")
    board.close()
    if value:
        return Outcome(_decode(value))
    if stopped is not None:
        return Outcome(f"stop: {str(stopped).splitlines()[0]}")
    return Outcome("no report")


def _decode(value: int) -> str:
    """riscv-tests' tohost protocol: 1 for a pass, (case << 1) | 1 for a failed case, and the
    case ORed with 1337 for an exception the test did not expect."""
    if value == 1:
        return "pass"
    if value & 1337 == 1337:
        return f"exception (tohost {value})"
    return f"fail {value >> 1}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("checkout", type=Path, help="a riscv-tests tree (with isa/)")
    parser.add_argument("--env", type=Path, help="the riscv-test-env tree (default: CHECKOUT/env)")
    parser.add_argument("--out", type=Path, default=ROOT / "build" / "riscv-tests", help="where the ELFs go")
    parser.add_argument("--suite", choices=("early-2017", "current"), default="early-2017",
                        help="which suite CHECKOUT holds, for the expected outcomes")
    parser.add_argument("--only", nargs="*", default=[], help="test names (rv64ui-p-add ...)")
    parser.add_argument("--json", type=Path, help="write the outcomes here")
    args = parser.parse_args(argv)
    env = args.env or args.checkout / "env"
    if not (args.checkout / "isa").is_dir() or not (env / "p" / "riscv_test.h").is_file():
        print(f"error: {args.checkout} has no isa/ or {env} no p/riscv_test.h", file=sys.stderr)
        return EXIT_USAGE
    expected = json.loads(EXPECTED.read_text())["suites"][args.suite]["not passing"]
    outcomes: dict[str, dict[str, str]] = {}
    different = 0
    for elf in build(args.checkout, env, args.out, set(args.only)):
        outcomes[elf.name] = {engine: run(elf, engine).text for engine in ENGINES}
        want = expected.get(elf.name, {}).get("outcome", "pass")
        wrong = [f"{engine} {text}" for engine, text in outcomes[elf.name].items() if text != want]
        if wrong:
            different += 1
            print(f"{elf.name}: expected {want}, got {'; '.join(wrong)}")
    passed = sum(all(text == "pass" for text in o.values()) for o in outcomes.values())
    as_expected = sum(name in expected and all(text == expected[name]["outcome"] for text in o.values())
                      for name, o in outcomes.items())
    print(f"{len(outcomes)} tests on {len(ENGINES)} engines: {passed} pass on both, "
          f"{as_expected} do not pass as expected, {different} differ from expected")
    if args.json:
        args.json.write_text(json.dumps(outcomes, indent=1, sort_keys=True) + "\n")
    return EXIT_DIFFERENT if different else EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
