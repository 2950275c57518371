"""Fuzzing of the input readers: generated and mutated scene.ini, .obj and .ppm files go through
the host's rules (reference/, which the card builder uses) and through the firmware's own
readers, called on the board model's CPU (tests/support/firmware_calls.py, no boot), with the board's
store checker on. For every input:

- host and firmware agree: both accept (the same counts, the same texels), or both refuse
  with the same words and line (`bad scene.ini line N: ...`, `bad model line N: ...`,
  `bad texture: ...`: the firmware's errors 9, 10 and 11);
- the firmware neither traps, nor runs away (an instruction budget), nor stores outside its
  buffers (`--check-writes`'s checker).

Decimal numbers, generated close to the single-precision edges where Python's float() and parse.S
round differently, go through reference.numbers and parse.S's parse_number: the same verdict and
the same double, bit for bit.

The firmware's console output is captured by making the UART take each byte at once, and a
fatal error is caught where errors.S ends its report (`error_end`), before it paints the screen.
FUZZ_EXAMPLES=N runs N examples of each (nightly use: see docs/guide/running-and-testing.md "Fuzzing").
"""
from __future__ import annotations

import os
import struct
from decimal import Decimal, localcontext
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from unicorn import riscv_const as rv

from emulator.cpu.hart import RunEnd
from firmware_calls import FirmwareCaller
from reference.numbers import parse_number
from reference.obj import ModelError, parse_obj
from reference.ppm import TextureError, parse_ppm
from reference.scene import KEYS, SceneError, parse_scene

EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "150"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                                       HealthCheck.data_too_large])
INSN_WFI = 0x1050_0073
BUDGET = 20_000_000
UARTHS_TXDATA = 0x00
SCENE_MODE = 0                         # firmware/include/scene.inc
MESH_TEX_PIXELS = 168
MESH_FCOUNT = 120
FILE_RECORD_ADDRESS, FILE_RECORD_SIZE = 0, 8


class ParserCaller:
    """The firmware's readers, one call at a time, on a fresh .bss and heap each time."""

    def __init__(self, elf: Path) -> None:
        self.caller = FirmwareCaller(elf, check_writes=True)
        board = self.caller.board
        self.console = bytearray()
        uart = board.uarths
        plain_read, plain_write = uart.read_register, uart.write_register

        def read(offset, reg, now):
            return 0 if offset == UARTHS_TXDATA else plain_read(offset, reg, now)

        def write(offset, reg, value, now):
            if offset == UARTHS_TXDATA:
                self.console.append(value & 0xFF)
            else:
                plain_write(offset, reg, value, now)

        uart.read_register, uart.write_register = read, write
        self.error_end = self.caller.symbol("error_end")
        self.caller.write(self.error_end, INSN_WFI.to_bytes(4, "little"))
        self.bss = (self.caller.symbol("__bss_start"), self.caller.symbol("__bss_end"))
        # an error report stopped at error_end still holds the console (console.S keeps its
        # owner in .data, which clearing .bss leaves alone)
        self.console_owner = self.caller.symbol("console_owner")

    def _fresh(self) -> None:
        start, end = self.bss
        self.caller.write(start, bytes(end - start))
        self.caller.write(self.console_owner, bytes(4))
        self.console.clear()
        self.caller.call("heap_init")
        # the heap's first bytes hold the wfi every call returns to (firmware_calls): keep
        # them out of the blocks the readers are given
        self.caller.call("heap_alloc", [self.caller.scratch - self.caller.return_address])

    def _place(self, data: bytes) -> int:
        """The bytes in a heap block, as scene.S would have loaded them."""
        address = self.caller.call("heap_alloc", [max(len(data), 1)]).a[0]
        assert address, "heap_alloc failed"
        self.caller.write(address, data)
        return address

    def run(self, routine: str, args: list[int]) -> str:
        """'ok' or the firmware's error line without 'error <code> ' (with the code first)."""
        caller, hart = self.caller, self.caller.hart
        try:
            caller.call(routine, args, budget=BUDGET)
            outcome = "ok"
        except AssertionError as failure:
            if hart.pc != self.error_end + 4:
                raise
            outcome = self.console.decode("latin-1").rsplit("\n", 1)[-1]
        stop = caller.board.write_watch.stray_store(hart)
        assert stop is None, f"{routine} stored outside the firmware's buffers: {stop}"
        return outcome

    def scene(self, text: bytes) -> str:
        self._fresh()
        caller = self.caller
        address = self._place(text)
        caller.call("scene_defaults")
        outcome = self.run("scene_parse", [address, len(text)])
        if outcome == "ok":
            outcome = self.run("scene_check_planes", [])
        return outcome

    def _record(self, name: str, data: bytes) -> None:
        record = self.caller.symbol(name)
        self.caller.write(record, struct.pack("<QQ", self._place(data), len(data)))

    def texture(self, data: bytes) -> tuple[str, np.ndarray | None]:
        self._fresh()
        self._record("scene_texture", data)
        outcome = self.run("ppm_parse_texture", [])
        if outcome != "ok":
            return outcome, None
        scene = self.caller.symbol("scene")
        raw = self.caller.read(scene, 176)
        width, height, pixels = struct.unpack_from("<IIQ", raw, 160)
        texels = np.frombuffer(self.caller.read(pixels, 2 * width * height), dtype="<u2")
        return outcome, texels.reshape(height, width)

    def number(self, text: bytes) -> tuple[int, int] | None:
        """parse.S parse_number on the text: (bytes it read, the IEEE bits of its double), or None
        when it refuses the text."""
        self._fresh()
        address = self._place(text)
        result = self.caller.call("parse_number", [address, address + len(text)], budget=BUDGET)
        stop = self.caller.board.write_watch.stray_store(self.caller.hart)
        assert stop is None, f"parse_number stored outside the firmware's buffers: {stop}"
        if result.a[1] != 0:
            return None
        return result.a[0] - address, self.caller.uc.reg_read(rv.UC_RISCV_REG_F10)

    def model(self, text: bytes) -> str:
        self._fresh()
        self._record("scene_model", text)
        outcome = self.run("obj_parse_model", [])
        if outcome != "ok":
            return outcome
        lines = self.console.decode("latin-1").split("\n")
        return next(line for line in lines if line.startswith("model: "))


@pytest.fixture(scope="module")
def parsers(firmware) -> ParserCaller:
    return ParserCaller(firmware)


# --------------------------------------------------------------------------- generators

NUMBERS = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False, width=32).map(repr),
    st.integers(-10**6, 10**6).map(str),
    st.sampled_from(["0", "-0", ".5", "5.", "1e38", "3.4e38", "3.5e38", "1e400", "1e-50", "-1.5e-3",
                     "+2", "1.", "e5", "1e", "--1", "1.2.3", "nan", "inf", "0x10", "1_0", "", "."]),
)
BLANKS = st.sampled_from([" ", "  ", "\t", " \t "])
ENDINGS = st.sampled_from(["\n", "\r\n", "\r", "\r\r\n", "\n\n"])


def _mutate(data: bytes, edits: list[tuple[int, int, bytes]]) -> bytes:
    """Each edit: at a relative position, delete some bytes and insert others."""
    out = bytearray(data)
    for where, delete, insert in edits:
        at = where % (len(out) + 1)
        out[at:at + delete] = insert
    return bytes(out)


EDITS = st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 3), st.binary(max_size=3)),
                 max_size=3)


@st.composite
def scene_texts(draw) -> bytes:
    lines = []
    for _ in range(draw(st.integers(0, 6))):
        key = draw(st.one_of(st.sampled_from(KEYS), st.sampled_from(["MODE", "Fov", "speed", ""])))
        words = draw(st.lists(st.one_of(NUMBERS, st.sampled_from(
            ["textured", "flat", "wireframe", "on", "off", "Yes", "affine", "gouraud", "table", "int16",
             "float32", "pixel", "#203040", "#20304", "model.obj", "a b.obj", "#"])), min_size=0, max_size=4))
        value = draw(BLANKS).join(words)
        comment = draw(st.sampled_from(["", " # note", "#"]))
        lines.append(f"{key}{draw(BLANKS)}={draw(BLANKS)}{value}{comment}{draw(ENDINGS)}")
    text = "".join(lines).encode("latin-1")
    return _mutate(text, draw(EDITS))


@st.composite
def obj_texts(draw) -> bytes:
    lines = []
    counts = {"v": 0, "vt": 0, "vn": 0}
    for _ in range(draw(st.integers(1, 10))):
        kind = draw(st.sampled_from(["v", "v", "vt", "vn", "f", "f", "#", "o", "usemtl", "s"]))
        if kind in counts:
            n = draw(st.integers(0, 8))
            words = [kind] + [draw(NUMBERS) for _ in range(n)]
            counts[kind] += 1
        elif kind == "f":
            corners = []
            for _ in range(draw(st.integers(0, 5))):
                index = st.integers(-4, 6).map(str)
                form = draw(st.sampled_from(["v", "v/t", "v//n", "v/t/n", "v/", "/t", "v//"]))
                corners.append(form.replace("v", draw(index)).replace("t", draw(index))
                               .replace("n", draw(index)))
            words = ["f"] + corners
        else:
            words = [kind, "name"]
        lines.append(draw(BLANKS).join(words) + draw(ENDINGS))
    return _mutate("".join(lines).encode("latin-1"), draw(EDITS))


@st.composite
def ppm_files(draw) -> bytes:
    magic = draw(st.sampled_from([b"P6", b"P3", b"P5", b"P", b"P68"]))
    width, height = draw(st.integers(0, 4)), draw(st.integers(0, 3))
    maxval = draw(st.sampled_from([0, 1, 15, 255, 256, 1000, 65535, 65536]))
    sep = lambda: draw(st.sampled_from([b" ", b"\n", b"\t", b"\r\n", b" # c\n", b"#c\n"]))  # noqa: E731
    header = magic + sep() + str(width).encode() + sep() + str(height).encode() + sep() + \
        str(maxval).encode()
    samples = width * height * 3 + draw(st.integers(-2, 2))
    if magic == b"P3":
        values = [draw(st.integers(0, max(maxval, 1) + 1)) for _ in range(max(samples, 0))]
        body = draw(st.sampled_from([b" ", b"\n"])) + b" ".join(str(v).encode() for v in values)
    else:
        wide = maxval > 255
        top = min(max(maxval, 1) + 1, 65535 if wide else 255)
        values = [draw(st.integers(0, top)) for _ in range(max(samples, 0))]
        body = draw(st.sampled_from([b"\n", b" ", b"#x\n"])) + b"".join(
            v.to_bytes(2 if wide else 1, "big") for v in values)
    return _mutate(header + body, draw(st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 2),
                                                           st.binary(max_size=2)), max_size=2)))


def _exact_digits(value: Decimal) -> tuple[str, int]:
    """(significant digits, q) with value = int(digits) x 10^q, for an exact finite decimal."""
    _, digits, q = value.normalize().as_tuple()
    return "".join(map(str, digits)), q


# Where the firmware's rounding of a decimal decides a verdict or a stored single: the overflow
# threshold (halfway between the largest single and 2^128), the largest single, the smallest
# normal and subnormal singles and half the latter (below it: zero), the tie just above 1
# (ambient <= 1) and just below 180 (fov < 180). Each is a finite decimal, written exactly.
with localcontext() as _exact:
    _exact.prec = 200
    EDGES = [_exact_digits(value) for value in (
        Decimal(2) ** 128 - Decimal(2) ** 103, Decimal(2) ** 128 - Decimal(2) ** 104,
        Decimal(2) ** -126, Decimal(2) ** -149, Decimal(2) ** -150,
        1 + Decimal(2) ** -24, 180 - Decimal(2) ** -17)]
DIGITS = st.sampled_from("0123456789")


@st.composite
def edge_decimals(draw) -> str:
    """A decimal agreeing with one of EDGES for its first 12 to 40 significant digits (mostly 16
    to 19: close enough for parse.S's truncation to 19 digits and its roundings in double to
    decide the single), 20 to 40 digits in all, written with a sign or none, the point anywhere,
    leading and trailing zeros, and an exponent that keeps its value."""
    edge, q = draw(st.sampled_from(EDGES))
    prefix = edge[:draw(st.one_of(st.integers(16, 19), st.integers(16, 19), st.integers(12, 40)))]
    digits = prefix + "".join(draw(st.lists(DIGITS, min_size=max(0, 20 - len(prefix)),
                                            max_size=max(0, 40 - len(prefix)))))
    q += len(edge) - len(digits)                # value ~ int(digits) x 10^q
    point = draw(st.integers(0, len(digits)))
    whole = "0" * draw(st.integers(0, 2)) + digits[:point]
    fraction = ("0" * draw(st.integers(0, 3)) if point == 0 else "") + digits[point:]
    trailing = draw(st.integers(0, 2))
    fraction += "0" * trailing
    text = whole + ("." + fraction if fraction or draw(st.booleans()) else "")
    exponent = q + len(fraction) - trailing
    if exponent or draw(st.booleans()):
        sign = "-" if exponent < 0 else draw(st.sampled_from(["", "+"]))
        text += draw(st.sampled_from("eE")) + sign + "0" * draw(st.integers(0, 2)) + str(abs(exponent))
    return draw(st.sampled_from(["", "+", "-"])) + text


@st.composite
def long_decimals(draw) -> str:
    """Any 1 to 40 digits, the point anywhere, any exponent up to beyond parse.S's cap."""
    digits = "".join(draw(st.lists(DIGITS, min_size=1, max_size=40)))
    point = draw(st.integers(0, len(digits)))
    text = draw(st.sampled_from(["", "+", "-"])) + digits[:point] + "." + digits[point:]
    exponent = draw(st.one_of(st.integers(-60, 60), st.integers(-400, 400), st.integers(-10**7, 10**7)))
    return text + f"e{exponent:+d}"


NUMBER_TOKENS = st.one_of(
    edge_decimals(), edge_decimals(), edge_decimals(), long_decimals(),
    st.floats(allow_nan=False, allow_infinity=False, width=32).map(repr),
    st.text(st.sampled_from("0123456789.eE+-"), min_size=1, max_size=12),     # mostly not numbers
)
NUMBER_FUZZ = settings(FUZZ, max_examples=int(os.environ.get("FUZZ_EXAMPLES", "100")))


# --------------------------------------------------------------------------- the properties

def host_scene(text: bytes) -> str:
    try:
        parse_scene(text)
    except SceneError as error:
        return f"error {error.firmware_error.code} {error}"
    return "ok"


def host_model(text: bytes) -> str:
    try:
        mesh = parse_obj(text)
    except ModelError as error:
        return f"error {error.firmware_error.code} {error}"
    # the parsers run on a cleared scene: mode textured, shading flat, so normals are counted
    # but not stored (obj.S keeps them only for Gouraud shading)
    return (f"model: {len(mesh.faces)} triangles, {len(mesh.vertices)} vertices, "
            f"{len(mesh.texcoords)} uv, {len(mesh.normals)} normals (not stored: shading flat)")


@FUZZ
@given(text=scene_texts())
def test_scene_ini_host_and_firmware_agree(parsers, text):
    assert parsers.scene(text) == host_scene(text)


@FUZZ
@given(text=obj_texts())
def test_obj_host_and_firmware_agree(parsers, text):
    assert parsers.model(text) == host_model(text)


@FUZZ
@given(data=ppm_files())
def test_ppm_host_and_firmware_agree(parsers, data):
    outcome, texels = parsers.texture(data)
    try:
        expected = parse_ppm(data)
    except TextureError as error:
        assert outcome == f"error 11 {error}"
        return
    assert outcome == "ok"
    assert np.array_equal(texels, expected)


@NUMBER_FUZZ
@given(token=NUMBER_TOKENS, after=st.sampled_from(["", " ", "\t", " 1"]))
def test_numbers_host_and_firmware_agree(parsers, token, after):
    """reference.numbers and parse.S's parse_number: the same verdict and, bit for bit, the same
    double, from which every range check and stored single of the readers follows."""
    value = parse_number(token)
    outcome = parsers.number((token + after).encode("ascii"))
    if value is None:
        assert outcome is None
    else:
        assert outcome == (len(token), struct.unpack("<Q", struct.pack("<d", value))[0]), value


def test_the_harness_sees_acceptance_and_each_kind_of_refusal(parsers):
    """The checks above can fail: known inputs give the firmware's known verdicts."""
    assert parsers.scene(b"mode = flat\nfov = 90\n") == "ok"
    assert parsers.scene(b"mode = flat\nfov = 200\n") == \
        "error 9 bad scene.ini line 2: bad value (fov must be between 0 and 180 degrees)"
    assert parsers.model(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n") == \
        "model: 1 triangles, 3 vertices, 0 uv, 0 normals (not stored: shading flat)"
    assert parsers.model(b"v 0 0 0\nv 3.5e38 0 0\n") == "error 10 bad model line 2: number out of range"
    outcome, texels = parsers.texture(b"P3 1 1 255 255 0 255")
    assert outcome == "ok" and texels.tolist() == [[0xF81F]]
    assert parsers.texture(b"P68 8 255\n")[0].startswith("error 11 bad texture: bad header")


# Inputs on which the fuzz stage found host and firmware disagreeing (each host reader now
# follows the firmware's order and precision): they stay checked whatever Hypothesis draws.
FOUND = [
    ("scene", b"light_levels = 0.0 :0.0\n"),        # the count before a bad later token
    ("scene", b"fov = 1e-50\n"),                    # ranges on the single the firmware stores
    ("scene", b"near = 1.00000001\nfar = 1.00000002\n"),
    ("scene", b"scale =\x85 \n"),                   # words split at spaces and tabs only
    ("scene", b"background = 1 2 1e400\n"),          # the host's check raised OverflowError
    ("model", b"v 3.5e38\n"),                       # the count of numbers before their range
    ("model", b"v 0.0 0.0 0.0 3.5e38\n"),           # the range only of the numbers kept
    ("model", b"v 0.0 0.0 0.0 0.0 0.0 0.0 0.0 e5\n"),   # any token past 7 numbers
    ("model", b"vt 0.0 0.0 0.0 0.0\rv\n"),
    ("model", b"f 0/\n"),                           # a corner read index by index
    ("model", b"v\r# name\n"),                      # a CR before a comment ends no line
    ("texture", b"P6 0 0 0"),                       # P6's whitespace after maxval first
    ("texture", b"P6 1 2 # c\n1#\x00\x00\x00\x00\x00\x00"),
    ("texture", b"P3 1 2 1 0 0 2 0"),               # P3 pixels checked as they are read
    ("texture", b"P3\r\n1 # c\n2#c\n1 0 0 2 0\x000 0"),
]


# Numbers on which Python's float() and parse.S disagree (the host's readers used float() before
# reference.numbers): (reader, text, the firmware's verdict, which the host now gives too).
FLOAT_DISAGREES = [
    # 19 digits: float() rounds to the largest single, parse.S's double to infinity
    ("model", b"v 3.402823567797336323e38 0 0\n", "error 10 bad model line 1: number out of range"),
    ("scene", b"scale = 3.402823567797336323e38\n",
     "error 9 bad scene.ini line 1: bad value (number out of range)"),
    # 18 digits, the reverse: float() beyond single precision, parse.S within
    ("model", b"v 3.40282356779733644e38 0 1\nv 0 1 0\nv 0 0 1\nf 1 2 3\n",
     "model: 1 triangles, 3 vertices, 0 uv, 0 normals (not stored: shading flat)"),
    # 55 digits: float() stores 1 + 2^-23 (above 1), parse.S's 19 digits store 1
    ("scene", b"ambient = 1.000000059604644886412927462515654042363166809082031251\n", "ok"),
    ("scene", b"near = 1\nfar = 1.000000059604644886412927462515654042363166809082031251\n",
     "error 9 bad scene.ini line 2: bad value (far must be greater than near)"),
    # a colour channel: a whole number by float(), not by parse.S (checked in double precision)
    ("scene", b"background = 1.00000000000000010 0 0\n",
     "error 9 bad scene.ini line 1: bad value (expected R G B with 0..255 each, or #RRGGBB)"),
]


@pytest.mark.parametrize("reader,data,verdict", FLOAT_DISAGREES)
def test_numbers_where_float_and_the_firmware_disagree(parsers, reader, data, verdict):
    host = host_scene(data) if reader == "scene" else host_model(data)
    assert host == verdict
    assert (parsers.scene(data) if reader == "scene" else parsers.model(data)) == verdict


@pytest.mark.parametrize("reader,data", FOUND)
def test_what_the_fuzz_stage_found(parsers, reader, data):
    if reader == "scene":
        assert parsers.scene(data) == host_scene(data)
    elif reader == "model":
        assert parsers.model(data) == host_model(data)
    else:
        try:
            parse_ppm(data)
            expected = "ok"
        except TextureError as error:
            expected = f"error {error.firmware_error.code} {error}"
        assert parsers.texture(data)[0] == expected
