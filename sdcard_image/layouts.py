"""Cards with the awkward layouts a FAT reader must cope with, for firmware tests.

Each helper works on an open `fat32.CardWriter` through pyfatfs operations, then checks the
result on the raw FAT (via `rawfat`, not pyfatfs) and raises `LayoutError` if the condition
did not come about, so a test never silently runs on an easy layout.

* `write_fragmented`: a file whose cluster chain has gaps (pieces written with spacer files
  between them, the spacers then deleted);
* `delete_leaving_entries`: deleted files whose 8.3 and LFN slots stay in the folder marked
  0xE5, in front of live entries;
* `fill_directory`: a folder whose entries span several clusters;
* `place_case_variants`: names differing only in case. FAT long names keep their case but
  compare case-insensitively, so "Cube.obj" and "cube.obj" cannot share a folder (a driver
  would open whichever comes first). Each variant therefore gets its own folder.

`build_special_card` makes one card with all of them and returns what is where.
"""
from __future__ import annotations

import random
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from . import rawfat
from .errors import OutputExistsError
from .fat32 import CardWriter
from .image import DEFAULT_SIZE_MIB


class LayoutError(RuntimeError):
    """A layout helper did not produce the condition it promises."""


# --- reading the raw FAT ---------------------------------------------------------------------

def cluster_chain(image: Path, card_path: str) -> list[int]:
    """The clusters of a file or folder, in chain order, read from the raw FAT."""
    with rawfat.Fat32Volume(image) as vol:
        entry = vol.lookup(card_path)
        first = vol.boot.root_cluster if entry is None else entry.first_cluster
        if entry is not None and not entry.is_dir and entry.size == 0:
            return []
        return vol.cluster_chain(first, card_path)


def is_fragmented(chain: list[int]) -> bool:
    """True if some cluster is not followed by the next cluster number."""
    return any(b != a + 1 for a, b in zip(chain, chain[1:]))


def directory_entries(image: Path, card_dir: str, include_deleted: bool = True
                      ) -> list[rawfat.DirEntry]:
    """The raw entries of a folder in on-disk order, deleted ones included by default."""
    with rawfat.Fat32Volume(image) as vol:
        entry = vol.lookup(card_dir)
        first = vol.boot.root_cluster if entry is None else entry.first_cluster
        return vol.dir_entries(first, include_deleted=include_deleted, what=card_dir)


def _join(card_dir: str, name: str) -> str:
    return f"{card_dir.rstrip('/')}/{name}"


# --- producing layouts -----------------------------------------------------------------------

def write_fragmented(writer: CardWriter, card_path: str, data: bytes, fragments: int = 3,
                     keep_spacers: bool = False) -> list[int]:
    """Writes `data` as a file whose chain has at least `fragments` - 1 gaps; returns the chain.

    The file is written in `fragments` cluster-aligned pieces; before each later piece a
    one-cluster spacer file is written, so pyfatfs' allocator (first free cluster onwards)
    continues the file after the spacer. The spacers are deleted afterwards (their clusters
    become free gaps) unless `keep_spacers`. The folder of `card_path` must exist.
    """
    per = writer.bytes_per_cluster
    if fragments < 2 or len(data) < fragments * per:
        raise ValueError(f"{fragments} fragments need at least {fragments * per} bytes")
    pieces_clusters = len(data) // per // fragments
    cut = [i * pieces_clusters * per for i in range(fragments)] + [len(data)]
    parent = card_path.rsplit("/", 1)[0]
    spacers = []
    writer.write(card_path, data[cut[0]:cut[1]])
    for i in range(1, fragments):
        spacer = _join(parent, f"spacer{i}.tmp")
        writer.write(spacer, b"\xAA" * per)
        spacers.append(spacer)
        writer.append(card_path, data[cut[i]:cut[i + 1]])
    if not keep_spacers:
        for spacer in spacers:
            writer.remove(spacer)
    writer.reopen()
    chain = cluster_chain(writer.image, card_path)
    gaps = sum(1 for a, b in zip(chain, chain[1:]) if b != a + 1)
    if gaps < fragments - 1:
        raise LayoutError(f"{card_path}: chain {chain[:8]}... has {gaps} gaps, wanted "
                          f"{fragments - 1}")
    with rawfat.Fat32Volume(writer.image) as vol:
        if vol.read(vol.lookup(card_path), card_path) != data:
            raise LayoutError(f"{card_path}: content differs after fragmented write")
    return chain


def delete_leaving_entries(writer: CardWriter, card_paths: list[str]) -> None:
    """Deletes files leaving their directory slots marked 0xE5 (see
    `CardWriter.remove_leaving_entries`). Do this last for a folder: pyfatfs rewrites a
    folder compacted (dropping the deleted slots) whenever it adds or removes an entry there."""
    writer.remove_leaving_entries(card_paths)
    for path in card_paths:
        parent, _, name = path.rpartition("/")
        raw = directory_entries(writer.image, parent or "/")
        if any(not e.deleted and rawfat.fat_fold(e.name) == rawfat.fat_fold(name) for e in raw):
            raise LayoutError(f"{path}: still listed after deletion")
        short = [e for e in raw if e.deleted]
        if not short:
            raise LayoutError(f"{parent or '/'}: no deleted entry left in the folder")


def fill_directory(writer: CardWriter, card_dir: str, min_clusters: int = 3,
                   name_pattern: str = "entry number {:03d}.txt",
                   content_for: Callable[[int], bytes] | None = None) -> dict[str, bytes]:
    """Adds small files to a folder (created if needed) until its entries span at least
    `min_clusters` clusters; returns {card path: content}. Long names (an LFN slot plus the
    8.3 slot each) make the folder grow quickly. `content_for(i)` gives file i's bytes."""
    writer.makedirs(card_dir)
    files: dict[str, bytes] = {}
    i = 0
    while True:
        path = _join(card_dir, name_pattern.format(i))
        content = content_for(i) if content_for else f"file {i} in {card_dir}\n".encode()
        writer.write(path, content)
        files[path] = content
        i += 1
        writer.flush()
        if len(cluster_chain(writer.image, card_dir)) >= min_clusters:
            return files
        if i > 100000:
            raise LayoutError(f"{card_dir}: does not grow past one cluster")


def place_case_variants(writer: CardWriter, card_dir: str, variants: list[str],
                        contents: list[bytes] | None = None) -> dict[str, bytes]:
    """Puts names differing only in case ("Cube.obj", "cube.obj", "CUBE.OBJ") on the card, each
    in its own subfolder of `card_dir` ("v1", "v2", ...), since one FAT folder cannot hold two
    of them. Returns {card path: content}; contents default to distinct bytes per variant."""
    folded = {rawfat.fat_fold(v) for v in variants}
    if len(folded) != 1:
        raise ValueError(f"{variants} are not case variants of one name")
    placed: dict[str, bytes] = {}
    for i, name in enumerate(variants, start=1):
        folder = _join(card_dir, f"v{i}")
        writer.makedirs(folder)
        content = contents[i - 1] if contents else f"variant {i}: {name}\n".encode()
        writer.write(_join(folder, name), content)
        placed[_join(folder, name)] = content
    return placed


# --- one card with everything ------------------------------------------------------------------

@dataclass
class SpecialCard:
    """What `build_special_card` put where (card paths -> contents)."""

    image: Path
    #: The fragmented file, its content and its cluster chain.
    fragmented_path: str
    fragmented_data: bytes
    fragmented_chain: list[int]
    #: Folder holding deleted entries, the deleted names and the files still there.
    deleted_dir: str
    deleted_paths: list[str]
    survivors: dict[str, bytes] = field(default_factory=dict)
    #: Folder whose entries span several clusters and its files.
    big_dir: str = ""
    big_dir_files: dict[str, bytes] = field(default_factory=dict)
    big_dir_clusters: list[int] = field(default_factory=list)
    #: Names differing only in case, each in its own folder.
    case_variants: dict[str, bytes] = field(default_factory=dict)

    def all_files(self) -> dict[str, bytes]:
        """Every live file on the card with its content."""
        files = {self.fragmented_path: self.fragmented_data}
        files.update(self.survivors)
        files.update(self.big_dir_files)
        files.update(self.case_variants)
        return files


def build_special_card(out: Path, size_mib: int = DEFAULT_SIZE_MIB, force: bool = False,
                       seed: int = 210) -> SpecialCard:
    """Builds a card with a fragmented file, deleted entries, a multi-cluster folder and
    case-variant names (each verified on the raw FAT). Deterministic content for `seed`."""
    out = Path(out)
    if out.exists() and not force:
        raise OutputExistsError(f"{out} exists; use --force to overwrite it")
    rng = random.Random(seed)
    tmp = out.with_name(f".{out.name}.layout.tmp")
    try:
        writer = CardWriter.create(tmp, size_mib)
        try:
            per = writer.bytes_per_cluster
            writer.makedirs("/frag")
            frag_data = rng.randbytes(per * 9 + 123)
            chain = write_fragmented(writer, "/frag/fragmented.bin", frag_data, fragments=3)

            writer.makedirs("/deleted")
            names = ["first deleted file.txt", "KEEP1.TXT", "second deleted.bin",
                     "kept long name.txt", "GONE.TXT"]
            contents = {f"/deleted/{n}": rng.randbytes(rng.randrange(1, 3 * per)) for n in names}
            for path, content in contents.items():
                writer.write(path, content)
            deleted = ["/deleted/first deleted file.txt", "/deleted/second deleted.bin",
                       "/deleted/GONE.TXT"]
            delete_leaving_entries(writer, deleted)
            survivors = {p: c for p, c in contents.items() if p not in deleted}

            big_files = fill_directory(writer, "/many", min_clusters=3)
            big_chain = cluster_chain(writer.image, "/many")
            variants = place_case_variants(writer, "/case", ["Cube.obj", "cube.obj", "CUBE.OBJ"])
        finally:
            writer.close()
        tmp.replace(out)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return SpecialCard(image=out, fragmented_path="/frag/fragmented.bin",
                       fragmented_data=frag_data, fragmented_chain=chain,
                       deleted_dir="/deleted", deleted_paths=deleted, survivors=survivors,
                       big_dir="/many", big_dir_files=big_files, big_dir_clusters=big_chain,
                       case_variants=variants)
