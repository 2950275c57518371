"""Builds the board model's native hooks: the instruction and block counters (emulator/_insn_counter.c,
emulator/_block_counter.c, sharing emulator/_counter.h), the
store checker of --check-writes (emulator/_write_watch.c) and the poll-loop and store-watch hooks
that let the harts see each other's stores (emulator/_poll_watch.c)."""
from setuptools import Extension, setup

setup(ext_modules=[Extension("emulator._insn_counter", ["emulator/_insn_counter.c", "emulator/_block_counter.c"],
                             depends=["emulator/_counter.h"]),
                   Extension("emulator._write_watch", ["emulator/_write_watch.c"]),
                   Extension("emulator._poll_watch", ["emulator/_poll_watch.c"])])
