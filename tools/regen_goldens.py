"""Regenerates golden frames from the current firmware, on purpose, and checks against them.

Run it (`make goldens`) only after a deliberate change to what the firmware draws, look at the
new images, and commit them with the change that explains them. It reports, per frame, whether
it is new, unchanged, or how many pixels changed, before replacing it.

    python tools/regen_goldens.py [SCENE ...]      (default: every scene in tests/support/golden_scenes.py)
    python tools/regen_goldens.py --folder DIR [--folder DIR ...] [--frames N] [--check]

The project's scenes' goldens live in tests/golden/<scene>/. A scene folder of one's own holds a
scene.ini and the files it names, laid out as they are to be on the card (its files and folders
go to the card's root); its goldens go to DIR/golden/. --check runs the firmware on the folder's
card against them instead of writing them (the board model's --golden: status 9 on a mismatch).

Exit statuses: EXIT_STATUS_DETAILS (the numbers are k210_common/exit_status.py's).
"""
from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "support"))
from emulator.frontends.golden import compare_frame  # noqa: E402
from k210_common.exit_status import EXIT_GOLDEN_MISMATCH, EXIT_OK, EXIT_USAGE, help_epilog  # noqa: E402
from golden_scenes import GOLDEN, SCENES, scene_card  # noqa: E402

FOLDER_GOLDEN = "golden"        # a scene folder's goldens: DIR/golden/frame_NNNN.png
DEFAULT_FOLDER_FRAMES = 4
# When this command returns each status; --help is made from it. A failed run of the board
# model passes its own status on (`python -m emulator run --help` lists them).
EXIT_STATUS_DETAILS: dict[int, str] = {
    EXIT_OK: "the goldens were written (or, with `--check`, every frame matches its golden)",
    EXIT_USAGE: "bad command line, an unknown scene, or a scene folder whose card cannot be built",
    EXIT_GOLDEN_MISMATCH: "`--check`: a frame differs from its golden (diff images in the board model's output)",
}


def regenerate(name: str, firmware: Path, work: Path) -> int:
    _, frames = SCENES[name]
    return write_goldens(name, firmware, scene_card(name, work), frames, GOLDEN / name, work / f"out-{name}")


def folder_card(folder: Path, work: Path) -> Path:
    """The card of a scene folder: its files and subfolders at the card's root (its goldens
    excepted). Raises ValueError naming what is wrong with the folder."""
    from sdcard_image import build_image
    if not folder.is_dir():
        raise ValueError(f"{folder}: no such folder")
    if not (folder / "scene.ini").is_file():
        raise ValueError(f"{folder}: no scene.ini in it (a scene folder holds scene.ini and the files it names)")
    inputs = sorted(p for p in folder.iterdir() if p.name != FOLDER_GOLDEN)
    card = work / f"{folder.resolve().name}.img"
    build_image(card, inputs, force=True, on_warning=lambda text: print(f"{folder}: {text}", file=sys.stderr))
    return card


def folder_goldens(folder: Path, firmware: Path, frames: int, work: Path, check: bool) -> int:
    try:
        card = folder_card(folder, work)
    except Exception as error:          # the card builder's own errors name file and line
        print(f"{folder}: cannot build its card: {error}", file=sys.stderr)
        return EXIT_USAGE
    golden = folder / FOLDER_GOLDEN
    if check:
        result = subprocess.run([sys.executable, "-m", "emulator", "run", str(firmware), "--sd", str(card),
                                 "--frames", str(frames), "--out", str(work / "check"), "--quiet",
                                 "--golden", str(golden)], cwd=ROOT)
        return result.returncode
    return write_goldens(str(folder), firmware, card, frames, golden, work / "out")


def write_goldens(name: str, firmware: Path, card: Path, frames: int, folder: Path, out: Path) -> int:
    """Runs the firmware on the card and writes its first `frames` frames into `folder`."""
    result = subprocess.run([sys.executable, "-m", "emulator", "run", str(firmware), "--sd", str(card), "--frames",
                             str(frames), "--out", str(out), "--quiet"], cwd=ROOT)
    if result.returncode != 0:
        print(f"{name}: the firmware run failed (exit {result.returncode}); its goldens are left unchanged",
              file=sys.stderr)
        return result.returncode
    folder.mkdir(parents=True, exist_ok=True)
    for n in range(frames):
        frame = f"frame_{n:04d}.png"
        new, old = out / frame, folder / frame
        if old.exists():
            comparison = compare_frame(n, new, old, out / f"diff_{n:04d}.png")
            state = "unchanged" if comparison.matches else f"{comparison.differing_pixels} pixels changed"
        else:
            state = "new"
        shutil.copyfile(new, old)
        print(f"{old}: {state}")
    return EXIT_OK


def main(argv: list[str]) -> int:
    import argparse
    parser = argparse.ArgumentParser(prog="tools/regen_goldens.py", description=__doc__.split("\n")[0],
                                     epilog=help_epilog(EXIT_STATUS_DETAILS) + "any other: the board model's "
                                     "status for a run that failed (python -m emulator run --help)\n",
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scenes", nargs="*", metavar="SCENE", help=f"project scenes ({', '.join(SCENES)})")
    parser.add_argument("--folder", action="append", default=[], type=Path, metavar="DIR",
                        help="a scene folder of one's own (scene.ini and its files); goldens in DIR/golden")
    parser.add_argument("--frames", type=int, default=DEFAULT_FOLDER_FRAMES,
                        help=f"frames per scene folder (default {DEFAULT_FOLDER_FRAMES})")
    parser.add_argument("--check", action="store_true",
                        help="with --folder: compare against DIR/golden instead of writing it")
    args = parser.parse_args(argv)
    if args.frames < 1:
        parser.error(f"--frames must be at least 1, not {args.frames}")
    if args.check and (args.scenes or not args.folder):
        parser.error("--check takes scene folders (--folder); the project's scenes are checked by make test")
    firmware = ROOT / "build" / "firmware.elf"
    folder_status = 0
    for folder in args.folder:
        with tempfile.TemporaryDirectory() as tmp:
            folder_status = folder_goldens(folder, firmware, args.frames, Path(tmp), args.check) or folder_status
    if args.folder and not args.scenes:
        if not args.check:
            print("review the images, then commit them together with the change that explains them")
        return folder_status
    names = args.scenes or list(SCENES)
    unknown = [n for n in names if n not in SCENES]
    if unknown:
        print(f"unknown scene(s): {', '.join(unknown)}; known: {', '.join(SCENES)}", file=sys.stderr)
        return EXIT_USAGE
    status = folder_status
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            status = regenerate(name, firmware, Path(tmp)) or status
    print("review the images, then commit them together with the change that explains them")
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
