"""The C extension (_insn_counter.c with _fast_engine.c) as Python sees it: ctypes mirrors of the
structures it shares with hart.py, and its functions' signatures. A field added on one side must be
added on the other in the same place; tests/unit/cpu/test_native_layout.py checks names, order and sizes."""
from __future__ import annotations

import ctypes

import unicorn
from unicorn.unicorn_py3 import unicorn as _ucpy

from . import _insn_counter, shared_memory

BTB_ENTRIES, BHT_ENTRIES, RAS_ENTRIES = 40, 128, 2     # _insn_counter.c's predictor sizes
BTB_INDEX_BUCKETS = 128
NO_LIMIT = 2**64 - 1


class Predictor(ctypes.Structure):
    """_insn_counter.c's predictor_t (Rocket's BTB, BHT and RAS)."""
    _fields_ = [("pc", ctypes.c_uint64 * BTB_ENTRIES), ("target", ctypes.c_uint64 * BTB_ENTRIES),
                ("valid", ctypes.c_uint8 * BTB_ENTRIES), ("is_jump", ctypes.c_uint8 * BTB_ENTRIES),
                ("is_return", ctypes.c_uint8 * BTB_ENTRIES), ("bht", ctypes.c_uint8 * BHT_ENTRIES),
                ("ras", ctypes.c_uint64 * RAS_ENTRIES), ("next_replace", ctypes.c_uint32),
                ("history", ctypes.c_uint32), ("ras_count", ctypes.c_uint32), ("ras_pos", ctypes.c_uint32),
                ("index", ctypes.c_uint8 * BTB_INDEX_BUCKETS)]


L1_SETS, L1_WAYS, L1_LINE_SHIFT, L1_HOT = 64, 8, 6, 512     # _caches.h's geometry, its hot lines' table
L1_DEVICE_WINDOWS = 32    # _caches.h: device windows timed


class L1Cache(ctypes.Structure):
    """_caches.h's l1_cache_t: one cache's tags (line address + 1, 0: invalid), by set then way."""
    _fields_ = [("line", ctypes.c_uint64 * (L1_SETS * L1_WAYS)), ("writable", ctypes.c_uint8 * (L1_SETS * L1_WAYS)),
                ("hot", ctypes.c_uint64 * L1_HOT), ("hot_writable", ctypes.c_uint64 * L1_HOT),
                ("lfsr", ctypes.c_uint32), ("pad", ctypes.c_uint32),
                ("lookups", ctypes.c_uint64), ("misses", ctypes.c_uint64), ("write_backs", ctypes.c_uint64)]


class L1Caches(ctypes.Structure):
    """_caches.h's l1_caches_t: a hart's two caches and what their misses cost."""


L1Caches._fields_ = [("icache", L1Cache), ("dcache", L1Cache), ("fetch_line", ctypes.c_uint64),
                     ("peer", ctypes.POINTER(L1Caches)), ("cached_base", ctypes.c_uint64),
                     ("cached_size", ctypes.c_uint64), ("uncached_base", ctypes.c_uint64),
                     ("uncached_size", ctypes.c_uint64), ("data_fill", ctypes.c_uint32),
                     ("write_back", ctypes.c_uint32), ("fetch_fill", ctypes.c_uint32), ("uncached", ctypes.c_uint32),
                     ("uncached_accesses", ctypes.c_uint64), ("flush_per_way", ctypes.c_uint32), ("acquired", ctypes.c_uint32), ("flushes", ctypes.c_uint64),
                     ("device_windows", ctypes.c_uint32), ("pad2", ctypes.c_uint32),
                     ("device_base", ctypes.c_uint64 * L1_DEVICE_WINDOWS),
                     ("device_size", ctypes.c_uint64 * L1_DEVICE_WINDOWS),
                     ("device_cost", ctypes.c_uint32 * L1_DEVICE_WINDOWS), ("device_accesses", ctypes.c_uint64)]


class Counter(ctypes.Structure):
    """_insn_counter.c's insn_counter_t."""
    _fields_ = [("executed", ctypes.c_uint64), ("limit", ctypes.c_uint64), ("stop", ctypes.c_void_p),
                ("loops", ctypes.c_void_p), ("loop_mask", ctypes.c_uint64), ("poll_report", ctypes.c_uint64),
                ("cycles", ctypes.c_uint64), ("cycle_limit", ctypes.c_uint64), ("table", ctypes.c_void_p),
                ("table_base", ctypes.c_uint64), ("table_end", ctypes.c_uint64), ("reg_read", ctypes.c_void_p),
                ("reg_x0", ctypes.c_int32), ("pending_kind", ctypes.c_int32), ("pending_pc", ctypes.c_uint64),
                ("pending_entry", ctypes.c_uint32), ("pending_penalty", ctypes.c_uint32), ("mispredicts", ctypes.c_uint64),
                ("stall_cycles", ctypes.c_uint64), ("predictor", Predictor), ("csr_sites", ctypes.c_void_p),
                ("csr_mask", ctypes.c_uint64), ("csr_report", ctypes.c_uint64), ("last_pc", ctypes.c_uint64),
                ("sram", ctypes.c_void_p), ("sram_base", ctypes.c_uint64), ("sram_alias", ctypes.c_uint64),
                ("sram_size", ctypes.c_uint64), ("misaligned_pc", ctypes.c_uint64),
                ("misaligned_address", ctypes.c_uint64), ("misaligned_store", ctypes.c_uint64),
                ("caches", ctypes.POINTER(L1Caches))]


counter_lib = ctypes.CDLL(_insn_counter.__file__)
COUNT_HOOK = ctypes.cast(counter_lib.count_instruction, ctypes.c_void_p)
counter_lib.fast_state_new.restype = ctypes.c_void_p
counter_lib.fast_state_new.argtypes = [ctypes.c_uint64, ctypes.c_void_p, ctypes.c_uint64, ctypes.c_uint64, ctypes.c_uint64,
                                        ctypes.c_void_p, ctypes.c_void_p]
counter_lib.fast_state_free.argtypes = [ctypes.c_void_p]
counter_lib.fast_forget_decodings.argtypes = [ctypes.c_void_p]
counter_lib.fast_statistics.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_uint64)]
counter_lib.fast_abandon.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
counter_lib.fast_set_windows.restype = ctypes.c_int
counter_lib.fast_set_windows.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_uint32]
counter_lib.decode_access_for_tests.argtypes = [ctypes.c_uint32, ctypes.c_uint32, ctypes.POINTER(ctypes.c_int64)]
counter_lib.struct_sizes_for_tests.argtypes = [ctypes.POINTER(ctypes.c_uint64)]
counter_lib.fast_set_write_watch.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
fast_step = _insn_counter.fast_step   # runs the fast engine, CPython's way of calling (see _insn_counter.c)
counter_lib.fast_run_alone.restype = ctypes.c_uint64
counter_lib.fast_run_alone.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_uint64,
                                        ctypes.c_void_p]
counter_lib.fast_run_pair.restype = None
counter_lib.fast_run_pair.argtypes = [ctypes.c_void_p] * 7


class DeviceStop(ctypes.Structure):
    """_fast_engine.c's device_access_t: the access the interpreter stopped at (STOP_DEVICE)."""
    _fields_ = [("address", ctypes.c_uint64), ("value", ctypes.c_uint64), ("next_pc", ctypes.c_uint64),
                ("width", ctypes.c_uint32), ("is_store", ctypes.c_uint32), ("window", ctypes.c_uint32),
                ("rd", ctypes.c_uint32), ("sign_bits", ctypes.c_uint32), ("pad", ctypes.c_uint32)]


class RepeatRecord(ctypes.Structure):
    """_fast_engine.c's repeat_t: a device load the interpreter answers again itself (arm_repeats)."""
    _fields_ = [("pc", ctypes.c_uint64), ("address", ctypes.c_uint64), ("value", ctypes.c_uint64),
                ("until", ctypes.c_uint64), ("width", ctypes.c_uint32), ("armed", ctypes.c_uint32),
                ("repeats", ctypes.c_uint32), ("needed", ctypes.c_uint32), ("answered", ctypes.c_uint32),
                ("polling", ctypes.c_uint32)]


class FastHead(ctypes.Structure):
    """The start of _fast_engine.c's fast_state_t: the hart's registers while the interpreter holds
    them, the device access it stopped at, the load it answers again itself."""
    _fields_ = [("x", ctypes.c_uint64 * 33), ("f", ctypes.c_uint64 * 32), ("pc", ctypes.c_uint64),
                ("mstatus", ctypes.c_uint64), ("fflags", ctypes.c_uint64), ("frm", ctypes.c_uint64),
                ("dev", DeviceStop), ("rep", RepeatRecord)]


# the most device events a plan of turns alone runs past (UARTHS's quiet byte ends: its FIFO's
# 8 bytes and the one on the wire); _turns.h's QUIET_ENDS_MAX
QUIET_ENDS_MAX = 16


class AlonePlan(ctypes.Structure):
    """_turns.h's alone_plan_t: the turns of a hart running alone (Scheduler._go_on_alone)."""
    _fields_ = [("anchor_time", ctypes.c_int64), ("anchor_cycles", ctypes.c_uint64), ("hz", ctypes.c_uint64),
                ("quantum", ctypes.c_uint64), ("outer", ctypes.c_int64), ("stop_at", ctypes.c_int64),
                ("max_turns", ctypes.c_uint64), ("t0", ctypes.c_int64), ("horizon", ctypes.c_int64),
                ("budget", ctypes.c_uint64), ("start_cycles", ctypes.c_uint64),
                ("start_executed", ctypes.c_uint64), ("turns", ctypes.c_uint64), ("handed_over", ctypes.c_uint64),
                ("end_time", ctypes.c_int64), ("tick_ends", ctypes.c_int64 * QUIET_ENDS_MAX),
                ("ticks", ctypes.c_uint64)]


class PairPlan(ctypes.Structure):
    """_turns.h's pair_plan_t: the turns of both harts running (Scheduler._go_on_paired)."""
    _fields_ = [("anchor_time", ctypes.c_int64 * 2), ("anchor_cycles", ctypes.c_uint64 * 2),
                ("time", ctypes.c_int64 * 2), ("hz", ctypes.c_uint64), ("quantum", ctypes.c_uint64),
                ("outer", ctypes.c_int64), ("stop_at", ctypes.c_int64), ("max_turns", ctypes.c_uint64),
                ("pc", ctypes.c_uint64 * 2), ("last", ctypes.c_uint64), ("t0", ctypes.c_int64),
                ("horizon", ctypes.c_int64), ("budget", ctypes.c_uint64), ("start_cycles", ctypes.c_uint64),
                ("start_executed", ctypes.c_uint64), ("turns", ctypes.c_uint64), ("handed_over", ctypes.c_uint64)]


def add_native_hook(uc: unicorn.Uc, kind: int, callback: int, user_data: ctypes.Structure, begin: int, end: int,
                    what: str) -> int:
    """Installs a hook written in C (callback: its address) on Unicorn's own hook list."""
    handle = ctypes.c_size_t()
    status = _ucpy.uclib.uc_hook_add(uc._uch, ctypes.byref(handle), kind, callback,
                                     ctypes.byref(user_data), ctypes.c_uint64(begin), ctypes.c_uint64(end))
    if status != 0:
        raise RuntimeError(f"cannot install {what}: unicorn status {status}")
    return handle.value


def address_table(addresses: list[int]) -> tuple[ctypes.Array, int]:
    """The native counter's table of CSR sites: u64 slots holding shared_memory.table_key of each
    (collision_free_size; an empty slot holds 0, which is no instruction's address). Returns
    (table, mask)."""
    keys = {shared_memory.table_key(address) for address in addresses}
    size = shared_memory.collision_free_size(list(keys))
    table = (ctypes.c_uint64 * size)()
    for key in keys:
        table[(key >> 1) & (size - 1)] = key
    return table, size - 1
