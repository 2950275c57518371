"""The host tools' failures in the user's terms: `python -m sdcard_image` refusing to replace an
input with the image and naming the output (never its temporary file) when writing fails, and
`python -m reference` on inputs that are not cards; each ends with its documented exit status
and no traceback, and each `--help` lists the statuses."""
from __future__ import annotations

import errno
import hashlib
import re
import subprocess
from pathlib import Path

import pytest

from emulator_runs import run_module as run_tool_module
from k210_common.exit_status import EXIT_CORRUPT_CARD, EXIT_USAGE, EXIT_WRITE_FAILED
from reference.cli import EXIT_STATUS_DETAILS
from sdcard_image import cli as sd_cli
from sdcard_image import fat32

TRIANGLE = b"v -1 -1 -2\nv 1 -1 -2\nv 0 1 -2\nf 1 2 3\n"


def run_module(module: str, *args: str | Path) -> subprocess.CompletedProcess:
    """`python -m module ARGS` in a process of its own (forked by the tests' run server)."""
    return run_tool_module(module, *args, timeout=120)


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


# --------------------------------------------------------------------------- sdcard_image build

def test_build_refuses_an_output_that_is_an_input(tmp_path):
    model = tmp_path / "X.obj"
    model.write_bytes(TRIANGLE)
    before = digest(model)
    result = run_module("sdcard_image", "build", "--force", model, model)
    assert result.returncode == EXIT_USAGE, result.stderr
    assert f"{model} is also an input: the image would replace it" in result.stderr
    assert "Traceback" not in result.stderr
    assert digest(model) == before


def test_build_refuses_an_output_reached_through_a_link_to_an_input(tmp_path):
    model = tmp_path / "X.obj"
    model.write_bytes(TRIANGLE)
    link = tmp_path / "link.img"
    link.symlink_to(model)
    result = run_module("sdcard_image", "build", "--force", link, model)
    assert result.returncode == EXIT_USAGE and "is also an input" in result.stderr
    assert model.read_bytes() == TRIANGLE


def test_build_refuses_an_output_inside_an_input_folder(tmp_path):
    folder = tmp_path / "assets"
    folder.mkdir()
    (folder / "model.obj").write_bytes(TRIANGLE)
    result = run_module("sdcard_image", "build", folder / "card.img", folder)
    assert result.returncode == EXIT_USAGE
    assert f"lies inside the input folder {folder}" in result.stderr
    assert sorted(p.name for p in folder.iterdir()) == ["model.obj"]


def test_build_write_failure_names_the_output_not_its_temporary_file(tmp_path, monkeypatch, capsys):
    """A full disk (ENOSPC while formatting) exits with write-failed naming the image the user asked for, and
    leaves neither the image nor a temporary file behind."""
    (tmp_path / "model.obj").write_bytes(TRIANGLE)
    out = tmp_path / "out" / "card.img"
    out.parent.mkdir()

    def full_disk(path, size_mib, **options):
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(fat32.CardWriter, "create", staticmethod(full_disk))
    status = sd_cli.main(["build", "-q", str(out), str(tmp_path / "model.obj")])
    err = capsys.readouterr().err
    assert status == EXIT_WRITE_FAILED
    assert f"cannot write {out} (64 MiB): No space left on device; nothing was written" in err
    assert ".tmp" not in err and "[Errno" not in err
    assert list(out.parent.iterdir()) == []


def test_build_into_a_folder_that_cannot_hold_files(tmp_path):
    (tmp_path / "model.obj").write_bytes(TRIANGLE)
    result = run_module("sdcard_image", "build", "/proc/card.img", tmp_path / "model.obj")
    assert result.returncode == EXIT_WRITE_FAILED
    assert "cannot write /proc/card.img: cannot create a file in /proc" in result.stderr
    assert "[Errno" not in result.stderr and "Traceback" not in result.stderr


def test_extract_write_failure_names_the_file(tmp_path, monkeypatch, capsys):
    from sdcard_image import build_image
    card = tmp_path / "card.img"
    (tmp_path / "model.obj").write_bytes(TRIANGLE)
    build_image(card, [tmp_path / "model.obj"])
    blocker = tmp_path / "blocked"
    blocker.write_text("a file where a folder is wanted")
    status = sd_cli.main(["extract", str(card), "/model.obj", str(blocker / "model.obj")])
    assert status == EXIT_USAGE and "folder does not exist" in capsys.readouterr().err

    def refuse(self, data):
        raise OSError(errno.EDQUOT, "Disk quota exceeded")

    monkeypatch.setattr(Path, "write_bytes", refuse)
    status = sd_cli.main(["extract", str(card), "--all", str(tmp_path / "all")])
    err = capsys.readouterr().err
    assert status == EXIT_WRITE_FAILED
    assert f"cannot write {tmp_path / 'all' / 'model.obj'}: Disk quota exceeded" in err


@pytest.mark.parametrize("command", [[], ["build"], ["list"], ["extract"]])
def test_sdcard_image_help_lists_every_exit_status(command):
    result = run_module("sdcard_image", *command, "--help")
    assert result.returncode == 0
    statuses = [line.split()[0] for line in result.stdout.split("exit status:")[1].splitlines()
                if re.match(r" {1,2}\d+  ", line)]
    assert statuses == [str(n) for n in sorted(sd_cli.EXIT_STATUS_DETAILS)]


# --------------------------------------------------------------------------- reference

@pytest.fixture(scope="module")
def unpartitioned(tmp_path_factory) -> Path:
    image = tmp_path_factory.mktemp("raw") / "blank.img"
    image.write_bytes(bytes(2 * 1024 * 1024))
    return image


def test_reference_on_a_card_without_a_partition_table(unpartitioned, tmp_path):
    result = run_module("reference", "render-card", unpartitioned, "--out", tmp_path / "out")
    assert result.returncode == EXIT_CORRUPT_CARD, result.stderr
    assert "Traceback" not in result.stderr
    assert f"{unpartitioned}: not a readable card image: no MBR signature" in result.stderr


def test_reference_missing_inputs_and_bad_output(tmp_path):
    result = run_module("reference", "render-card", tmp_path / "none.img", "--out", tmp_path)
    assert result.returncode == EXIT_USAGE and "none.img: no such image file" in result.stderr
    result = run_module("reference", "render", tmp_path / "none", "--out", tmp_path)
    assert result.returncode == EXIT_USAGE and "none: no such folder" in result.stderr
    folder = tmp_path / "card"
    folder.mkdir()
    (folder / "model.obj").write_bytes(TRIANGLE)
    (folder / "scene.ini").write_text("mode = flat\n")
    (folder / "texture.ppm").write_bytes(b"P3 1 1 1 1 1 1")
    taken = tmp_path / "taken"
    taken.write_text("not a folder")
    result = run_module("reference", "render", folder, "--out", taken)
    assert result.returncode == EXIT_WRITE_FAILED and f"--out {taken}: exists and is not a folder" in result.stderr
    assert "Traceback" not in result.stderr


def test_reference_help_describes_options_and_statuses():
    for command in ([], ["render"], ["render-card"]):
        result = run_module("reference", *command, "--help")
        assert result.returncode == 0
        statuses = [line.split()[0] for line in result.stdout.split("exit status:")[1].splitlines()
                    if re.match(r" {1,2}\d+  ", line)]
        assert statuses == [str(n) for n in sorted(EXIT_STATUS_DETAILS)]
    result = run_module("reference", "render", "--help")
    for option in ("--out DIR", "--frames N", "--first K", "--quiet"):
        line = next(l for l in result.stdout.splitlines() if l.strip().startswith(option))
        assert len(line.split(option, 1)[1].strip()) > 10, f"{option} has no description"
