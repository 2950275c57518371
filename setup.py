"""Builds the board model's native parts: the instruction counter and the fast engine
(emulator/cpu/_insn_counter.c, emulator/cpu/_fast_engine.c and the turns it runs, emulator/cpu/_turns.c, sharing _caches.h, _counter.h, _fast_engine.h, _rocket_timing.h and _turns.h), the
store checker of --check-writes (emulator/cpu/_write_watch.c, sharing emulator/cpu/_write_check.h with the fast engine) and the poll-loop and store-watch hooks
that let the harts see each other's stores (emulator/cpu/_poll_watch.c)."""
from setuptools import Extension, setup

setup(ext_modules=[Extension("emulator.cpu._insn_counter", ["emulator/cpu/_insn_counter.c", "emulator/cpu/_fast_engine.c", "emulator/cpu/_turns.c"],
                             depends=["emulator/cpu/_caches.h", "emulator/cpu/_counter.h", "emulator/cpu/_fast_engine.h", "emulator/cpu/_rocket_timing.h", "emulator/cpu/_write_check.h", "emulator/cpu/_host_fp.h", "emulator/cpu/_turns.h"], libraries=["m"],
                             # the guest's floating point is the host's: no fused or reordered operations; the
                             # fast engine's entry points exported, its helpers not
                             extra_compile_args=["-O2", "-ffp-contract=off", "-fno-fast-math", "-fvisibility=hidden"]),
                   Extension("emulator.cpu._write_watch", ["emulator/cpu/_write_watch.c"], depends=["emulator/cpu/_write_check.h"]),
                   Extension("emulator.cpu._poll_watch", ["emulator/cpu/_poll_watch.c"])])
