"""Regenerates the golden frames in tests/golden/ from the current firmware, on purpose.

Run it (`make goldens`) only after a deliberate change to what the firmware draws, look
at the new images, and commit them with the change that explains them. It reports
which frames changed and by how many pixels before replacing them.
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
from conftest import CARD, GOLDEN, GOLDEN_FRAMES  # noqa: E402
from emulator.golden import compare_frame  # noqa: E402


def main() -> int:
    firmware = ROOT / "build" / "firmware.elf"
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        result = subprocess.run([sys.executable, "-m", "emulator", "run", str(firmware), "--sd", str(CARD), "--frames",
                                 str(GOLDEN_FRAMES), "--out", str(out), "--quiet"], cwd=ROOT)
        if result.returncode != 0:
            print(f"the firmware run failed (exit {result.returncode}); goldens left unchanged", file=sys.stderr)
            return result.returncode
        GOLDEN.mkdir(parents=True, exist_ok=True)
        for n in range(GOLDEN_FRAMES):
            name = f"frame_{n:04d}.png"
            new, old = out / name, GOLDEN / name
            if old.exists():
                comparison = compare_frame(n, new, old, out / f"diff_{n:04d}.png")
                state = "unchanged" if comparison.matches else f"{comparison.differing_pixels} pixels changed"
            else:
                state = "new"
            shutil.copyfile(new, old)
            print(f"{old.relative_to(ROOT)}: {state}")
    print("review the images, then commit them together with the change that explains them")
    return 0


if __name__ == "__main__":
    sys.exit(main())
