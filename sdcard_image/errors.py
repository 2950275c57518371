"""Errors of the card-image tool, each tied to the exit status the command line reports.

Callers of the Python API catch `SdImageError` (or one subclass); the command line turns
`exit_status` into the process status so scripts can tell the failures apart. The numbers are
k210_common/exit_status.py's, shared with the project's other commands.
"""
from __future__ import annotations

from pathlib import Path

from k210_common.exit_status import (EXIT_BAD_INPUT, EXIT_CARD_TOO_SMALL, EXIT_CORRUPT_CARD, EXIT_INTERNAL,
                                     EXIT_OUTPUT_EXISTS, EXIT_USAGE, EXIT_WRITE_FAILED)


class SdImageError(Exception):
    """Base class: a failure the user can act on (never a bug in this tool)."""

    exit_status = EXIT_INTERNAL


class UsageError(SdImageError):
    """Bad arguments: wrong option value, colliding card names, a path not on the card."""

    exit_status = EXIT_USAGE


class BadInputError(SdImageError):
    """An input file is broken (OBJ, PPM, image, scene.ini); names the file and line."""

    exit_status = EXIT_BAD_INPUT

    def __init__(self, path: Path | str, message: str, line: int | None = None) -> None:
        self.path = Path(path)
        self.line = line
        self.reason = message
        where = f"{path}:{line}" if line is not None else f"{path}"
        super().__init__(f"{where}: {message}")


class OutputExistsError(SdImageError):
    """The output exists and --force was not given."""

    exit_status = EXIT_OUTPUT_EXISTS


class ImageTooSmallError(SdImageError):
    """The content does not fit in the requested image size."""

    exit_status = EXIT_CARD_TOO_SMALL


class CorruptImageError(SdImageError):
    """An image to read is not an MBR-partitioned FAT32 card, or its FAT32 is damaged."""

    exit_status = EXIT_CORRUPT_CARD


class OutputWriteError(SdImageError):
    """An output (the image, or an extracted file) could not be written: disk full,
    permissions, a read-only file system. Names the output, never a temporary file."""

    exit_status = EXIT_WRITE_FAILED
