"""Builds the board model's native hooks: the instruction counter (emulator/_insn_counter.c) and
the store checker of --check-writes (emulator/_write_watch.c)."""
from setuptools import Extension, setup

setup(ext_modules=[Extension("emulator._insn_counter", ["emulator/_insn_counter.c"]),
                   Extension("emulator._write_watch", ["emulator/_write_watch.c"])])
