"""cpu/native.py's ctypes mirrors against the C structures they mirror: the same field names in the
same order as the C source declares them, and the sizes the compiler gives the C side
(struct_sizes_for_tests). A field added, removed, reordered or widened on one side only fails here
instead of shifting every field after it."""
from __future__ import annotations

import ctypes
import re

import pytest

from suite import ROOT
from emulator.cpu import native
from unicorn import riscv_const

CPU = ROOT / "emulator" / "cpu"


def c_fields(struct: str) -> list[str]:
    """The field names of `typedef struct ... { ... } struct;` in the extension's sources, in order."""
    source = "".join((CPU / name).read_text() for name in ("_caches.h", "_counter.h", "_fast_engine.h", "_turns.h", "_fast_engine.c"))
    source = re.sub(r"/\*.*?\*/", "", source, flags=re.S)
    match = re.search(r"typedef struct(?: \w+)? \{([^{}]*)\} " + struct + ";", source)
    assert match, f"no typedef of {struct}"
    names = []
    for statement in match.group(1).split(";"):
        parts = statement.strip().split(",")
        if not parts[0]:
            continue
        names.append(re.search(r"(\w+)\s*(?:\[[^\]]*\])?\s*$", parts[0]).group(1))
        names += [re.match(r"\s*\**\s*(\w+)", part).group(1) for part in parts[1:]]
    return names


def c_sizes() -> list[int]:
    out = (ctypes.c_uint64 * 9)()
    native.counter_lib.struct_sizes_for_tests(out)
    return list(out)


MIRRORS = [(native.Predictor, "predictor_t", 0), (native.Counter, "insn_counter_t", 1),
           (native.DeviceStop, "device_access_t", 2), (native.RepeatRecord, "repeat_t", 3),
           (native.AlonePlan, "alone_plan_t", 5), (native.L1Cache, "l1_cache_t", 6),
           (native.L1Caches, "l1_caches_t", 7), (native.PairPlan, "pair_plan_t", 8)]


@pytest.mark.parametrize("mirror, struct, index", MIRRORS, ids=[m[1] for m in MIRRORS])
def test_each_mirror_has_the_c_fields_and_size(mirror, struct, index):
    assert [name for name, _ in mirror._fields_] == c_fields(struct)
    assert ctypes.sizeof(mirror) == c_sizes()[index]


def test_the_fast_state_head_is_the_start_of_fast_state_t():
    names = [name for name, _ in native.FastHead._fields_]
    assert c_fields("fast_state_t")[:len(names)] == names
    assert c_fields("fast_state_t")[len(names)] == "windows"
    assert ctypes.sizeof(native.FastHead) == c_sizes()[4]


def test_the_field_parser_sees_multiple_declarators_and_arrays():
    # repeat_t declares several fields a line; fast_state_t has pointers and arrays
    assert c_fields("repeat_t")[:4] == ["pc", "address", "value", "until"]
    assert "code_hi" in c_fields("fast_state_t") and "window_end" in c_fields("fast_state_t")


def test_the_unicorn_register_ids_the_fast_engine_uses_are_unicorn_s():
    """_fast_engine.c names Unicorn's register ids itself (it does not include unicorn/riscv.h):
    each must be the id the Python binding of the installed Unicorn gives."""
    source = (CPU / "_fast_engine.c").read_text()
    ids = dict(re.findall(r"^#define UC_(\w+) (\d+)$", source, re.MULTILINE))
    assert set(ids) == {"X1", "FFLAGS", "FRM", "MSTATUS", "F0", "PC"}
    for name, value in ids.items():
        assert getattr(riscv_const, f"UC_RISCV_REG_{name}") == int(value), name
