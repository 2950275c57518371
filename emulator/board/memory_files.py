"""Memory-only files a process fills once and maps privately for each board: SRAM's power-on
pattern (memory.py) and the erased flash (flash_image.py). A board then starts without filling
megabytes (the suite makes thousands of boards), and only the pages it writes are copied, when it
writes them."""
from __future__ import annotations

import mmap
import os
from typing import Callable


def memory_file(name: str, contents: Callable[[], bytes]) -> int | None:
    """A memory-only file holding contents(), kept open for the process (a forked one inherits it);
    None where the system has none (os.memfd_create is Linux's) or will not hold it: a memory file
    counts against the file size limit (RLIMIT_FSIZE, `ulimit -f`), and past it the write fails
    (CPython ignores SIGXFSZ). The caller then keeps a copy of its own in memory."""
    if not hasattr(os, "memfd_create"):
        return None
    try:
        descriptor = os.memfd_create(name, os.MFD_CLOEXEC)
    except OSError:                 # (a sandbox without it, no descriptors or memory left)
        return None
    try:
        with open(descriptor, "wb", closefd=False) as file:     # (a buffered write writes it all)
            file.write(contents())
    except BaseException as error:
        os.close(descriptor)
        if isinstance(error, OSError):
            return None
        raise
    return descriptor


def private_mapping(descriptor: int, size: int) -> mmap.mmap:
    """The file's first `size` bytes, mapped copy-on-write: writes stay in this mapping."""
    return mmap.mmap(descriptor, size, flags=mmap.MAP_PRIVATE, prot=mmap.PROT_READ | mmap.PROT_WRITE)
