"""Command line: `python -m sdcard_image build|list|extract ...`.

Exit statuses: EXIT_STATUS_HELP. Messages go to stderr; the build report and listings to
stdout.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from . import fat32
from .convert import parse_scene_args, parse_texture_size
from k210_common.exit_status import (EXIT_BAD_INPUT, EXIT_CARD_TOO_SMALL, EXIT_CORRUPT_CARD, EXIT_INTERNAL,
                                     EXIT_OK, EXIT_OUTPUT_EXISTS, EXIT_USAGE, EXIT_WRITE_FAILED, help_epilog)
from .errors import OutputExistsError, OutputWriteError, SdImageError, UsageError
from .image import DEFAULT_SIZE_MIB, build_image, extract_all, list_image, read_file

PROG = "python -m sdcard_image"

# When this command returns each status (k210_common/exit_status.py holds the numbers and
# names); --help and sdcard_image/README.md's table are made from it (tests/unit/shared/test_exit_status.py)
EXIT_STATUS_DETAILS: dict[int, str] = {
    EXIT_OK: "done",
    EXIT_INTERNAL: "an internal error of this tool (a bug: please report it with the command line)",
    EXIT_USAGE: "bad command line: an unknown option or bad value, a missing or unreadable input, names that "
                "collide on the card, the output among the inputs, a `--scene` value the firmware would refuse "
                "(build: a model or texture the scene names, or the firmware's default model, that is not on "
                "the card, named with its key), no such file on the card",
    EXIT_BAD_INPUT: "build: a bad input file (`.obj`, `.ppm`, image, `scene.ini`), named with its line; a "
                    "`scene.ini` naming a model or texture that is not on the card (with its key and line)",
    EXIT_OUTPUT_EXISTS: "the output exists: add `--force` to replace it",
    EXIT_CARD_TOO_SMALL: "build: the content does not fit in the `--size` given (or in the largest card)",
    EXIT_CORRUPT_CARD: "list, extract: the image is not an MBR-partitioned FAT32 card, or is damaged (the message "
                       "names the broken structure)",
    EXIT_WRITE_FAILED: "an output could not be written (disk full, permissions): the message names the image or "
                       "the extracted file, never a temporary file; a failed build leaves nothing behind, "
                       "extract names the file it stopped at",
}

EXIT_STATUS_HELP = help_epilog(EXIT_STATUS_DETAILS)


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # argparse exits 2 too; keep its usage line
        self.print_usage(sys.stderr)
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message}\n")


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog=PROG, description="Build and read SD card images (MBR + FAT32) for "
                                            "the K210 renderer.",
                     epilog=EXIT_STATUS_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    sub_options = {"epilog": EXIT_STATUS_HELP,
                   "formatter_class": argparse.RawDescriptionHelpFormatter}

    b = sub.add_parser("build", help="build a card image from files and folders",
                       description="Each PATH (file, or folder copied with its subfolders) "
                                   "lands at the card root under its own name. .obj files are "
                                   "checked, images converted to binary PPM, .ppm validated.",
                       **sub_options)
    b.add_argument("out", type=Path, metavar="OUT.img")
    b.add_argument("paths", type=Path, nargs="*", metavar="PATH")
    b.add_argument("--size", type=int, metavar="MiB",
                   help=f"image size in MiB ({fat32.min_image_mib()}..{fat32.max_image_mib()}; "
                        f"default {DEFAULT_SIZE_MIB}, larger if the content needs it)")
    b.add_argument("--force", action="store_true", help="overwrite an existing image")
    b.add_argument("--texture-size", metavar="WxH",
                   help="resize converted images to WxH (PPM inputs are kept as they are)")
    b.add_argument("--scene", action="append", default=[], metavar="KEY=VALUE",
                   help="write /scene.ini with one 'key = value' line per option")
    b.add_argument("--layout", choices=fat32.LAYOUTS, default=fat32.LAYOUT_FATGEN103,
                   help="how the FAT32 partition is laid out: fatgen103 (the default: Microsoft's "
                        "specification's cluster sizes, as pyfatfs formats it) or mkfs.fat (exactly as "
                        "dosfstools' mkfs.fat -F 32 formats a card's partition on Linux: its cluster size, "
                        "reserved sectors, FAT size and geometry fields; needs dosfstools)")
    b.add_argument("--quiet", "-q", action="store_true", help="no report on stdout")

    ls = sub.add_parser("list", help="list the folders and files on a card image", **sub_options)
    ls.add_argument("image", type=Path, metavar="IMG")

    ex = sub.add_parser("extract", help="copy files from a card image",
                        description="extract IMG CARD_PATH OUT copies one file ('-' as OUT "
                                    "writes to stdout; an existing folder as OUT receives it "
                                    "under its name); extract IMG --all DIR copies everything.",
                        **sub_options)
    ex.add_argument("image", type=Path, metavar="IMG")
    ex.add_argument("card_path", nargs="?", metavar="CARD_PATH")
    ex.add_argument("out", nargs="?", metavar="OUT")
    ex.add_argument("--all", type=Path, metavar="DIR", dest="all_dir",
                    help="extract every folder and file into DIR")
    ex.add_argument("--force", action="store_true", help="overwrite existing files")
    return parser


def _build(args: argparse.Namespace) -> None:
    texture = parse_texture_size(args.texture_size) if args.texture_size else None
    scene = parse_scene_args(args.scene) if args.scene else None
    placed = build_image(args.out, args.paths, size_mib=args.size, force=args.force,
                         scene=scene, texture_size=texture,
                         on_warning=lambda m: print(f"warning: {m}", file=sys.stderr), layout=args.layout)
    if not args.quiet:
        for p in placed:
            print(p.report_line())
        total = sum(p.size for p in placed)
        print(f"{args.out}: {len(placed)} files, {total} bytes")


def _list(args: argparse.Namespace) -> None:
    for entry in list_image(args.image):
        size = "<DIR>" if entry.is_dir else str(entry.size)
        print(f"{size:>12}  {entry.path}{'/' if entry.is_dir else ''}")


def _extract(args: argparse.Namespace) -> None:
    if args.all_dir is not None:
        if args.card_path or args.out:
            raise UsageError("extract --all DIR takes no CARD_PATH or OUT")
        for entry in extract_all(args.image, args.all_dir, force=args.force):
            if not entry.is_dir:
                print(f"{entry.path} -> {args.all_dir / entry.path.lstrip('/')}")
        return
    if not args.card_path or not args.out:
        raise UsageError("extract needs IMG CARD_PATH OUT (or IMG --all DIR)")
    data = read_file(args.image, args.card_path)
    if args.out == "-":
        sys.stdout.buffer.write(data)
        sys.stdout.buffer.flush()
        return
    out = Path(args.out)
    if out.is_dir():
        out = out / args.card_path.replace("\\", "/").rstrip("/").rsplit("/", 1)[-1]
    if (out.exists() or out.is_symlink()) and not args.force:
        raise OutputExistsError(f"{out} exists; use --force to overwrite it")
    if not out.parent.is_dir():
        raise UsageError(f"{out.parent}: folder does not exist")
    try:
        out.write_bytes(data)
    except OSError as exc:
        raise OutputWriteError(f"cannot write {out}: {exc.strerror or exc}") from None


def main(argv: list[str] | None = None) -> int:
    """Runs the command line; returns the exit status."""
    parser = _parser()
    # argparse stops filling `paths` at the first option, so `build OUT --force A B` would
    # leave A and B over: collect such left-over paths for `build`, refuse anything else
    args, extra = parser.parse_known_args(argv)
    if extra and (args.command != "build" or any(e.startswith("-") for e in extra)):
        parser.error(f"unrecognized arguments: {' '.join(extra)}")
    if extra:
        args.paths = list(args.paths) + [Path(e) for e in extra]
    try:
        {"build": _build, "list": _list, "extract": _extract}[args.command](args)
    except SdImageError as exc:
        print(f"{PROG} {args.command}: error: {exc}", file=sys.stderr)
        return exc.exit_status
    except BrokenPipeError:
        return EXIT_OK
    except OSError as exc:  # an input or the image could not be read
        what = f"{exc.filename}: " if exc.filename else ""
        print(f"{PROG} {args.command}: error: {what}{exc.strerror or exc}", file=sys.stderr)
        return EXIT_USAGE
    return EXIT_OK
