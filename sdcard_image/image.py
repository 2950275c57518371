"""Building card images and reading them back: the Python API behind the command line."""
from __future__ import annotations

import math
import os
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from . import fat32, rawfat
from .convert import CardPlan, PlacedFile, plan_card
from .errors import (CorruptImageError, ImageTooSmallError, OutputExistsError, OutputWriteError,
                     UsageError)

#: Default card size. 64 MiB is the smallest round size whose partition pyfatfs formats as a
#: proper FAT32 (126 990 clusters of 512 bytes, well above FAT32's 65 525 minimum) and still
#: builds and checks in a fraction of a second. Larger content grows the card in 64 MiB steps.
DEFAULT_SIZE_MIB = 64
SIZE_STEP_MIB = 64


def clusters_needed(plan: CardPlan, bytes_per_cluster: int) -> int:
    """Clusters the plan takes: file data plus every folder's entries (root included).

    Folder sizes count each entry's LFN slots as `fat32.dir_slots` does, so this is exact or
    slightly above what pyfatfs allocates.
    """
    def clusters(nbytes: int) -> int:
        return math.ceil(nbytes / bytes_per_cluster)

    slots: dict[str, int] = {"": 1}  # root: the volume label entry
    for d in plan.dirs:
        slots[d] = 2  # "." and ".."
    for path in plan.dirs + [p.card_path for p, _ in plan.files]:
        parent, _, name = path.rpartition("/")
        slots[parent] = slots.get(parent, 0) + fat32.dir_slots(name)
    total = sum(max(1, clusters(n * rawfat.DIR_ENTRY_SIZE)) for n in slots.values())
    total += sum(clusters(p.size) for p, _ in plan.files)
    return total


def _fits(plan: CardPlan, size_mib: int, layout: str = fat32.LAYOUT_FATGEN103) -> tuple[bool, int, int]:
    geo = fat32.image_geometry(size_mib, layout)
    need = clusters_needed(plan, geo.bytes_per_cluster)
    return need <= geo.cluster_count, need, geo.cluster_count


def choose_size(plan: CardPlan, size_mib: int | None, layout: str = fat32.LAYOUT_FATGEN103) -> int:
    """The image size in MiB: `size_mib` if the content fits (else `ImageTooSmallError`),
    or the default grown in 64 MiB steps until it fits."""
    lo, hi = fat32.min_image_mib(), fat32.max_image_mib()
    if size_mib is not None:
        if not lo <= size_mib <= hi:
            raise UsageError(f"--size {size_mib}: a FAT32 card built here is {lo}..{hi} MiB")
        ok, need, have = _fits(plan, size_mib, layout)
        if not ok:
            geo = fat32.image_geometry(size_mib, layout)
            raise ImageTooSmallError(
                f"content needs {need} clusters of {geo.bytes_per_cluster} bytes but a "
                f"{size_mib} MiB card has {have}; use --size {_smallest_fit(plan, size_mib, layout)} "
                f"or more (or leave --size out)")
        return size_mib
    size = DEFAULT_SIZE_MIB
    while size <= hi:
        if _fits(plan, size, layout)[0]:
            return size
        size += SIZE_STEP_MIB
    raise ImageTooSmallError(f"content does not fit on the largest card built here ({hi} MiB)")


def _smallest_fit(plan: CardPlan, start: int, layout: str = fat32.LAYOUT_FATGEN103) -> int:
    """Smallest size above `start` MiB that holds the plan (binary search: capacity grows with
    size, give or take the slack of the cluster-size steps, which the final check covers)."""
    lo, hi = start + 1, fat32.max_image_mib()
    while lo < hi:
        mid = (lo + hi) // 2
        if _fits(plan, mid, layout)[0]:
            hi = mid
        else:
            lo = mid + 1
    while lo < fat32.max_image_mib() and not _fits(plan, lo, layout)[0]:
        lo += 1
    return lo


def write_plan(writer: fat32.CardWriter, plan: CardPlan) -> None:
    """Writes folders, then each folder's files. In every folder, names that are their own
    8.3 name go first, so generated "~N" short names can never take a real name."""
    for d in sorted(plan.dirs, key=lambda p: (p.count("/"), _order_key(p))):
        writer.makedirs(d)
    for placed, data in sorted(plan.files, key=lambda f: _order_key(f[0].card_path)):
        writer.write(placed.card_path, data)


def _order_key(card_path: str) -> tuple[str, bool, str]:
    parent, _, name = card_path.rpartition("/")
    return parent, not fat32.fits_8dot3(name), name


def verify_image(image: Path, plan: CardPlan) -> None:
    """Reads the built image back with the raw reader and compares with the plan: every file
    byte for byte, every folder present, and no name reachable twice in a folder."""
    with rawfat.Fat32Volume(image) as vol:
        found = {f.path: f for f in vol.walk()}
        for d in plan.dirs:
            if d not in found or not found[d].is_dir:
                raise RuntimeError(f"verification: folder {d} missing from {image}")
        for placed, data in plan.files:
            entry = found.get(placed.card_path)
            if entry is None or entry.is_dir:
                raise RuntimeError(f"verification: {placed.card_path} missing from {image}")
            if vol.read(entry.entry, placed.card_path) != data:
                raise RuntimeError(f"verification: {placed.card_path} differs in {image}")
        by_folder: dict[str, set[str]] = {}
        for path, f in found.items():
            parent = path.rpartition("/")[0]
            names = by_folder.setdefault(parent, set())
            for n in {rawfat.fat_fold(f.entry.name), rawfat.fat_fold(f.entry.short_name_str)}:
                if n in names:
                    raise RuntimeError(f"verification: name {n} used twice in {parent or '/'}")
                names.add(n)


def build_image(out: Path, inputs: list[Path], size_mib: int | None = None, force: bool = False,
                scene: dict[str, str] | None = None,
                texture_size: tuple[int, int] | None = None,
                on_warning: Callable[[str], None] | None = None,
                layout: str = fat32.LAYOUT_FATGEN103) -> list[PlacedFile]:
    """Builds an SD card image at `out` from files and folders, each at the card root.

    The image gets an MBR with one FAT32 partition (type 0x0C, LBA 2048 to the end), filled
    with pyfatfs. OBJ files are checked, images converted to P6 PPM (resized to
    `texture_size`), PPMs validated, `scene` written as /scene.ini. The image is written to a
    temporary file next to `out` and renamed into place, so a failure leaves no partial image.

    Raises `UsageError`, `BadInputError`, `OutputExistsError` (out exists, no `force`),
    `ImageTooSmallError`. Notes about inputs that are accepted but probably not what the
    user meant go to `on_warning` (default: `warnings.warn`). Returns the placed files in
    card order.
    """
    out = Path(out)
    if out.is_dir():
        raise UsageError(f"{out} is a folder; give the image file name")
    if not out.parent.is_dir():
        raise UsageError(f"{out.parent}: folder does not exist")
    if (out.exists() or out.is_symlink()) and not force:
        raise OutputExistsError(f"{out} exists; use --force to overwrite it")
    if not inputs and not scene:
        raise UsageError("nothing to put on the card: give files or folders (or --scene)")
    _refuse_output_among_inputs(out, [Path(p) for p in inputs])
    plan = plan_card([Path(p) for p in inputs], scene=scene, texture_size=texture_size)
    for message in plan.warnings:
        if on_warning is not None:
            on_warning(message)
        else:
            warnings.warn(message, stacklevel=2)
    if layout not in fat32.LAYOUTS:
        raise UsageError(f"layout {layout!r}: one of {', '.join(fat32.LAYOUTS)}")
    size = choose_size(plan, size_mib, layout)
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent)
    except OSError as exc:
        raise OutputWriteError(f"cannot write {out}: cannot create a file in {out.parent}: "
                               f"{exc.strerror}") from None
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        writer = fat32.CardWriter.create(tmp, size, layout=layout)
        try:
            write_plan(writer, plan)
        finally:
            writer.close()
        verify_image(tmp, plan)
        if out.exists() and not force:
            raise OutputExistsError(f"{out} appeared while building; use --force to overwrite")
        os.chmod(tmp, 0o666 & ~_umask())  # as a plain open() would create it
        os.replace(tmp, out)
    except OSError as exc:
        # The user named `out`; the temporary file next to it is an implementation detail
        tmp.unlink(missing_ok=True)
        raise OutputWriteError(f"cannot write {out} ({size} MiB): {exc.strerror or exc}; "
                               f"nothing was written") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return sorted((p for p, _ in plan.files), key=lambda p: p.card_path)


def _refuse_output_among_inputs(out: Path, inputs: list[Path]) -> None:
    """Refuses an output that is one of the inputs or lies inside an input folder: the build
    would replace an input with the image, or put the previous image on the new card."""
    target = out.resolve()
    for src in inputs:
        if not (src.exists() or src.is_symlink()):
            continue  # reported as missing by the planner
        real = src.resolve()
        same = real == target or (out.exists() and os.path.samefile(src, out))
        if same:
            raise UsageError(f"{out} is also an input: the image would replace it (give the "
                             f"image another name)")
        if src.is_dir() and target.is_relative_to(real):
            raise UsageError(f"{out} lies inside the input folder {src}: the card would hold "
                             f"its own image (write the image outside {src})")


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


# --- reading -------------------------------------------------------------------------------

@dataclass(frozen=True)
class CardEntry:
    """A file or folder on a card, as `list_image` reports it."""

    path: str
    size: int
    is_dir: bool
    short_name: str


def open_volume(image: Path) -> rawfat.Fat32Volume:
    """Opens an image read-only; a missing or unreadable file is a `UsageError`."""
    image = Path(image)
    if image.is_dir():
        raise UsageError(f"{image} is a folder, not an image file")
    try:
        return rawfat.Fat32Volume(image)
    except FileNotFoundError:
        raise UsageError(f"{image}: no such image file") from None
    except PermissionError:
        raise UsageError(f"{image}: permission denied") from None


def list_image(image: Path) -> list[CardEntry]:
    """Every folder and file on the card, depth first ("/models", "/models/cube.obj", ...).

    Raises `CorruptImageError` naming what is wrong with a damaged image.
    """
    with open_volume(image) as vol:
        entries = []
        for f in vol.walk():
            if not f.is_dir:
                # Reading each chain proves the listed size is really there.
                chain = vol.cluster_chain(f.entry.first_cluster, f.path) if f.size else []
                if len(chain) * vol.boot.bytes_per_cluster < f.size:
                    raise CorruptImageError(f"{f.path}: size {f.size} but only {len(chain)} "
                                            f"clusters in its chain")
            entries.append(CardEntry(path=f.path, size=f.size, is_dir=f.is_dir,
                                     short_name=f.entry.short_name_str))
        return entries


def read_file(image: Path, card_path: str) -> bytes:
    """The content of one file on the card. Names match case-insensitively, as on FAT.

    Raises `UsageError` if there is no such file, `CorruptImageError` for a damaged image.
    """
    with open_volume(image) as vol:
        try:
            entry = vol.lookup(card_path)
        except FileNotFoundError as exc:
            raise UsageError(f"{image}: {exc}") from None
        if entry is None or entry.is_dir:
            raise UsageError(f"{image}: {card_path} is a folder, not a file")
        return vol.read(entry, card_path)


def extract_all(image: Path, dest: Path, force: bool = False) -> list[CardEntry]:
    """Copies every folder and file of the card under `dest` (created if needed).

    Existing files are only overwritten with `force` (else `OutputExistsError`, checked
    before anything is written).
    """
    dest = Path(dest)
    with open_volume(image) as vol:
        files = list(vol.walk())
        if not force:
            for f in files:
                target = dest / f.path.lstrip("/")
                if not f.is_dir and (target.exists() or target.is_symlink()):
                    raise OutputExistsError(f"{target} exists; use --force to overwrite")
        if dest.exists() and not dest.is_dir():
            raise UsageError(f"{dest} exists and is not a folder")
        done = []
        target = dest
        try:
            dest.mkdir(parents=True, exist_ok=True)
            for f in files:
                target = dest / f.path.lstrip("/")
                if f.is_dir:
                    target.mkdir(parents=True, exist_ok=True)
                else:
                    data = vol.read(f.entry, f.path)
                    target.parent.mkdir(parents=True, exist_ok=True)
                    target.write_bytes(data)
                done.append(CardEntry(path=f.path, size=f.size, is_dir=f.is_dir,
                                      short_name=f.entry.short_name_str))
        except OSError as exc:
            raise OutputWriteError(f"cannot write {target}: {exc.strerror or exc} ({len(done)} "
                                   f"of {len(files)} entries extracted)") from None
        return done
