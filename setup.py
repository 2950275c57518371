"""Builds the board model's native parts: the instruction counter and the fast engine
(emulator/_insn_counter.c, emulator/_fast_engine.c, sharing emulator/_counter.h, _fast_engine.h and _rocket_timing.h), the
store checker of --check-writes (emulator/_write_watch.c, sharing emulator/_write_check.h with the fast engine) and the poll-loop and store-watch hooks
that let the harts see each other's stores (emulator/_poll_watch.c)."""
from setuptools import Extension, setup

setup(ext_modules=[Extension("emulator._insn_counter", ["emulator/_insn_counter.c", "emulator/_fast_engine.c"],
                             depends=["emulator/_counter.h", "emulator/_fast_engine.h", "emulator/_rocket_timing.h", "emulator/_write_check.h"], libraries=["m"],
                             # the guest's floating point is the host's: no fused or reordered operations; the
                             # fast engine's entry points exported, its helpers not
                             extra_compile_args=["-O2", "-ffp-contract=off", "-fno-fast-math", "-fvisibility=hidden"]),
                   Extension("emulator._write_watch", ["emulator/_write_watch.c"], depends=["emulator/_write_check.h"]),
                   Extension("emulator._poll_watch", ["emulator/_poll_watch.c"])])
