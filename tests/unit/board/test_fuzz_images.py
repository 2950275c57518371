"""The fuzz stage's images (issue 35): damaged ELF files and raw images of any bytes either load or
are refused as bad input naming what is wrong (BadInput: status 6), and one that loads runs until
a documented end (a frame, a trap, a hang, an unmodelled access: a BoardStop) or the time asked;
never another exception, which the command line would report as an internal error.

FUZZ_EXAMPLES=N runs N examples of each instead of the default (docs/guide/running-and-testing.md: "Fuzzing")."""
from __future__ import annotations

import os
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from emulator.board import Board
from emulator.errors import BadInput, BoardStop
from emulator.vtime import PS_PER_US
from k210_fixtures import program

EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "60"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
RUN_FOR = 100 * PS_PER_US
# values that break readers: zero, all ones, the top bit, lengths past the file or the address space
BREAKING = st.sampled_from([b"\x00", b"\xff", b"\x80", b"\x7f", b"\xff" * 8, b"\x00" * 8,
                            (1 << 63).to_bytes(8, "little"), (0x8000_0000).to_bytes(8, "little")])
PROGRAM = Path(program("""
    li      a0, 5
    la      t0, value
    sd      a0, 0(t0)
""", data="value: .dword 0\n")).read_bytes()
PHOFF = int.from_bytes(PROGRAM[0x20:0x28], "little")
SHOFF = int.from_bytes(PROGRAM[0x28:0x30], "little")
PH_BYTES = 56 * int.from_bytes(PROGRAM[0x38:0x3A], "little")
SH_BYTES = 64 * int.from_bytes(PROGRAM[0x3C:0x3E], "little")
# where a damaged byte matters most: the ELF header, the program headers, the section headers
OFFSETS = st.one_of(st.integers(0, 63), st.integers(PHOFF, PHOFF + PH_BYTES - 1),
                    st.integers(SHOFF, SHOFF + SH_BYTES - 1), st.integers(0, len(PROGRAM) - 1))


def loads_or_is_refused(path: Path) -> str:
    """What the command line would do with the image: "refused" (BadInput), or "ran" to a stop
    or the time asked. Any other exception fails the test."""
    try:
        board = Board(str(path), cold=True)
    except BadInput as error:
        assert str(error), "a refusal must say what is wrong"
        return "refused"
    try:
        board.run_until(RUN_FOR)
    except BoardStop:
        pass
    finally:
        board.close()
    return "ran"


@FUZZ
@given(edits=st.lists(st.tuples(OFFSETS, st.one_of(BREAKING, st.binary(min_size=1, max_size=8))),
                      min_size=1, max_size=6),
       cut=st.one_of(st.none(), st.integers(0, len(PROGRAM) - 1)))
def test_a_damaged_elf_loads_or_is_bad_input(tmp_path_factory, edits, cut):
    data = bytearray(PROGRAM)
    for offset, value in edits:
        data[offset:offset + len(value)] = value
    if cut is not None:
        del data[cut:]
    path = tmp_path_factory.mktemp("elf") / "damaged.elf"
    path.write_bytes(bytes(data))
    loads_or_is_refused(path)


@FUZZ
@given(data=st.binary(max_size=4096))
def test_a_raw_image_of_any_bytes_runs_or_is_bad_input(tmp_path_factory, data):
    path = tmp_path_factory.mktemp("raw") / "image.bin"
    path.write_bytes(data)
    outcome = loads_or_is_refused(path)
    if not data.startswith(b"\x7fELF"):           # (an ELF by its magic, whatever its name: load_firmware)
        assert outcome == ("refused" if not data else "ran")


def test_the_undamaged_program_runs():
    """(The mutations start from a program that loads and runs.)"""
    import tempfile
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "fine.elf"
        path.write_bytes(PROGRAM)
        assert loads_or_is_refused(path) == "ran"
