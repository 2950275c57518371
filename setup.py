"""Builds the board model's native instruction counter (see emulator/_insn_counter.c)."""
from setuptools import Extension, setup

setup(ext_modules=[Extension("emulator._insn_counter", ["emulator/_insn_counter.c"])])
