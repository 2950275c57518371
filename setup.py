"""Builds the board model's native hooks: the instruction counter (emulator/_insn_counter.c), the
store checker of --check-writes (emulator/_write_watch.c) and the poll-loop and store-watch hooks
that let the harts see each other's stores (emulator/_poll_watch.c)."""
from setuptools import Extension, setup

setup(ext_modules=[Extension("emulator._insn_counter", ["emulator/_insn_counter.c"]),
                   Extension("emulator._write_watch", ["emulator/_write_watch.c"]),
                   Extension("emulator._poll_watch", ["emulator/_poll_watch.c"])])
