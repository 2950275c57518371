"""Regenerates the golden frames in tests/golden/<scene>/ from the current firmware, on purpose.

Run it (`make goldens`) only after a deliberate change to what the firmware draws, look at the
new images, and commit them with the change that explains them. It reports, per frame, whether
it is new, unchanged, or how many pixels changed, before replacing it.

    python tools/regen_goldens.py [SCENE ...]      (default: every scene in tests/golden_scenes.py)
"""
from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))
from emulator.golden import compare_frame  # noqa: E402
from golden_scenes import GOLDEN, SCENES, scene_card  # noqa: E402


def regenerate(name: str, firmware: Path, work: Path) -> int:
    _, frames = SCENES[name]
    card = scene_card(name, work)
    out = work / f"out-{name}"
    result = subprocess.run([sys.executable, "-m", "emulator", "run", str(firmware), "--sd", str(card), "--frames",
                             str(frames), "--out", str(out), "--quiet"], cwd=ROOT)
    if result.returncode != 0:
        print(f"{name}: the firmware run failed (exit {result.returncode}); its goldens are left unchanged",
              file=sys.stderr)
        return result.returncode
    folder = GOLDEN / name
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
        print(f"{old.relative_to(ROOT)}: {state}")
    return 0


def main(argv: list[str]) -> int:
    names = argv or list(SCENES)
    unknown = [n for n in names if n not in SCENES]
    if unknown:
        print(f"unknown scene(s): {', '.join(unknown)}; known: {', '.join(SCENES)}", file=sys.stderr)
        return 2
    firmware = ROOT / "build" / "firmware.elf"
    status = 0
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            status = regenerate(name, firmware, Path(tmp)) or status
    print("review the images, then commit them together with the change that explains them")
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
