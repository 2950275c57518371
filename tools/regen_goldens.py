"""Regenerates golden frames from the current firmware, on purpose, and checks against them.

Run it (`make goldens`) only after a deliberate change to what the firmware draws, look at the
new images, and commit them with the change that explains them. It reports, per frame, whether
it is new, unchanged, or how many pixels changed, before replacing it.

    python tools/regen_goldens.py [SCENE ...] [--out OUT]   (default: every scene in tests/support/golden_scenes.py)
    python tools/regen_goldens.py --folder DIR [--folder DIR ...] [--frames N] [--check] [--out OUT]

The project's scenes' goldens live in tests/golden/<scene>/. A scene folder of one's own holds a
scene.ini and the files it names, laid out as they are to be on the card (its files and folders
go to the card's root); its goldens go to DIR/golden/. --check runs the firmware on the folder's
card against them instead of writing them (the board model's --golden: status 9 on a mismatch).

Each run's output (frames, run.json, console.log, and the diff image of every frame that changed
or differs) stays in OUT/<scene> (OUT/<the folder's name> for a scene folder), where the messages
say it is: OUT is build/goldens by default, build/golden-check with --check.

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
DEFAULT_OUT = ROOT / "build" / "goldens"                # the runs' output, one folder a scene
DEFAULT_CHECK_OUT = ROOT / "build" / "golden-check"     # the same with --check
# When this command returns each status; --help is made from it. A failed run of the board
# model passes its own status on (`python -m emulator run --help` lists them).
EXIT_STATUS_DETAILS: dict[int, str] = {
    EXIT_OK: "the goldens were written (or, with `--check`, every frame matches its golden)",
    EXIT_USAGE: "bad command line, an unknown scene, or a scene folder whose card cannot be built",
    EXIT_GOLDEN_MISMATCH: "`--check`: a frame differs from its golden (its diff image in `OUT/<folder name>`, "
                          "build/golden-check/... by default, kept after the command and named by its messages)",
}


def regenerate(name: str, firmware: Path, work: Path, out: Path) -> int:
    _, frames = SCENES[name]
    return write_goldens(name, firmware, scene_card(name, work), frames, GOLDEN / name, out)


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


def folder_goldens(folder: Path, firmware: Path, frames: int, work: Path, check: bool, out: Path) -> int:
    """Writes (or, `check`, checks) a scene folder's goldens; the run's output goes to `out`."""
    try:
        card = folder_card(folder, work)
    except Exception as error:          # the card builder's own errors name file and line
        print(f"{folder}: cannot build its card: {error}", file=sys.stderr)
        return EXIT_USAGE
    golden = folder / FOLDER_GOLDEN
    if check:
        result = subprocess.run([sys.executable, "-m", "emulator", "run", str(firmware), "--sd", str(card),
                                 "--frames", str(frames), "--out", str(out), "--quiet",
                                 "--golden", str(golden)], cwd=ROOT)
        if result.returncode == EXIT_GOLDEN_MISMATCH:
            print(f"{folder}: frames differ from {golden} (status {EXIT_GOLDEN_MISMATCH}, golden-mismatch): "
                  f"the run's frames and diff images are in {out}", file=sys.stderr)
        elif result.returncode == EXIT_OK:
            print(f"{folder}: every frame matches {golden} (the run's output in {out})")
        return result.returncode
    return write_goldens(str(folder), firmware, card, frames, golden, out)


def out_folders(out: Path, names: list[str]) -> list[Path]:
    """One output folder in `out` per scene or scene folder, named after it (a name taken twice
    gets -2, -3, ...)."""
    taken: set[str] = set()
    folders = []
    for name in names:
        unique, n = name, 1
        while unique in taken:
            n += 1
            unique = f"{name}-{n}"
        taken.add(unique)
        folders.append(out / unique)
    return folders


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
            diff = out / f"diff_{n:04d}.png"
            comparison = compare_frame(n, new, old, diff)
            state = "unchanged" if comparison.matches else f"{comparison.differing_pixels} pixels changed" + \
                (f" (diff image {diff})" if diff.exists() else "")
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
    parser.add_argument("--out", type=Path, metavar="OUT",
                        help="where each run's output (frames, diff images, run.json) is kept, one folder a scene "
                             f"(default {DEFAULT_OUT.relative_to(ROOT)}, with --check "
                             f"{DEFAULT_CHECK_OUT.relative_to(ROOT)})")
    args = parser.parse_args(argv)
    if args.frames < 1:
        parser.error(f"--frames must be at least 1, not {args.frames}")
    if args.check and (args.scenes or not args.folder):
        parser.error("--check takes scene folders (--folder); the project's scenes are checked by make test")
    firmware = ROOT / "build" / "firmware.elf"
    out = (args.out or (DEFAULT_CHECK_OUT if args.check else DEFAULT_OUT)).resolve()
    names = args.scenes or ([] if args.folder else list(SCENES))
    outs = out_folders(out, [folder.resolve().name for folder in args.folder] + names)
    folder_outs, scene_outs = outs[:len(args.folder)], outs[len(args.folder):]
    folder_status = 0
    for folder, folder_out in zip(args.folder, folder_outs):
        with tempfile.TemporaryDirectory() as tmp:
            folder_status = folder_goldens(folder, firmware, args.frames, Path(tmp), args.check,
                                           folder_out) or folder_status
    if args.folder and not args.scenes:
        if not args.check:
            print("review the images, then commit them together with the change that explains them")
        return folder_status
    unknown = [n for n in names if n not in SCENES]
    if unknown:
        print(f"unknown scene(s): {', '.join(unknown)}; known: {', '.join(SCENES)}", file=sys.stderr)
        return EXIT_USAGE
    status = folder_status
    with tempfile.TemporaryDirectory() as tmp:
        for name, scene_out in zip(names, scene_outs):
            status = regenerate(name, firmware, Path(tmp), scene_out) or status
    print("review the images, then commit them together with the change that explains them")
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
