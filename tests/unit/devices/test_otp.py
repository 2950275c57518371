"""The OTP (devices/otp.py) read as the Kendryte SDK's otp.c of September 2018 reads it: the
hardware-driven read (otp_read_byte) and the CPU-driven one (otp_soft_read); blank unless --otp
gives its content; the AES key never given out; programming a clear stop."""
from __future__ import annotations

import json

import pytest

from suite import run_emulator
from emulator.devices import otp as o
from emulator.errors import UnmodelledAccess
from k210_fixtures import idle_elf, make_board  # noqa: F401


def read_bytes(otp, address: int, length: int) -> tuple[list[int], bool]:
    """otp_read_byte, register by register: (the bytes, whether the address was refused)."""
    otp.write(o.CLE, 4, 0, 0)
    otp.write(o.MODE, 4, 0, 0)
    otp.write(o.WRG_ADR_FLAG, 4, 0, 0)
    otp.write(o.CEB, 4, 0, 0)
    out = []
    for n in range(length):
        assert otp.read(o.ADR_IN_FLAG, 4, 0) == 1
        if n == length - 1:
            otp.write(o.OFFSET["otp_last_dat"], 4, 1, 0)
        otp.write(o.APB_ADR, 4, 8 * (address + n), 0)
        assert otp.read(o.DATA_RDY, 4, 0) == 1
        if otp.read(o.WRG_ADR_FLAG, 4, 0) == 1:
            return out, True
        out.append(otp.read(o.DATA, 4, 0))
    return out, False


def test_reads_give_the_content_and_a_blank_otp_says_so(idle_elf):
    board = make_board(idle_elf, cold=False, otp=bytes(range(16)) * 4, otp_source="a test")
    assert read_bytes(board.otp, 5, 4) == ([5, 6, 7, 8], False)
    blank = make_board(idle_elf, cold=False)
    assert read_bytes(blank.otp, 0x3AD0, 3) == ([0, 0, 0], False)
    assert any("blank" in text and "--otp" in text for text in blank.warnings)


def test_the_cpu_driven_read(idle_elf):
    board = make_board(idle_elf, cold=False, otp=b"\x00\x11\x22\x33")
    otp = board.otp
    otp.write(o.OFFSET["otp_ceb_cpu"], 4, 0, 0)
    got = []
    for n in range(4):
        otp.write(o.ADR_CPU, 4, 8 * n, 0)
        otp.write(o.READEN_CPU, 4, 1, 0)
        got.append(otp.read(o.DAT_CPU, 4, 0))
        otp.write(o.READEN_CPU, 4, 0, 0)
    assert got == [0x00, 0x11, 0x22, 0x33]


def test_the_aes_key_is_never_given_out(idle_elf):
    board = make_board(idle_elf, cold=False, otp=b"\x5A" * o.SIZE_BYTES)
    assert read_bytes(board.otp, o.KEY_ADDRESS - 1, 2) == ([0x5A], True)


@pytest.mark.parametrize("name, value", [("otp_pgmen_cpu", 1), ("otp_test_mode", 0x24), ("otp_mode", 2)])
def test_programming_and_test_modes_stop_clearly(idle_elf, name, value):
    board = make_board(idle_elf, cold=False)
    with pytest.raises(UnmodelledAccess, match="OTP"):
        board.otp.write(o.OFFSET[name], 4, value, 0)


def test_an_otp_file_larger_than_the_otp_is_bad_input(idle_elf, tmp_path):
    (tmp_path / "otp.bin").write_bytes(b"\0" * (o.SIZE_BYTES + 1))
    run = run_emulator("run", idle_elf, "--otp", str(tmp_path / "otp.bin"), "--until", "0.001", "--quiet",
                       "--out", str(tmp_path / "out"))
    assert run.returncode == 6 and "more than the OTP's 16384" in run.stderr
    (tmp_path / "otp.bin").write_bytes(b"\1\2")
    run = run_emulator("run", idle_elf, "--otp", str(tmp_path / "otp.bin"), "--until", "0.001", "--quiet",
                       "--out", str(tmp_path / "out"))
    assert run.returncode == 0, run.stderr
    assert json.loads((tmp_path / "out" / "run.json").read_text())["exit"] == "ok"


def test_otp_init_writes_every_register_it_clears(idle_elf):
    """The SDK's otp_init (and its status handshakes) write registers the hardware sets: taken, with
    no warning (a strict run would stop at a read-only register)."""
    board = make_board(idle_elf, cold=False, strict=True)
    for name in ("otp_cpu_ctrl", "otp_thershold", "data_blk_ctrl", "gb_otp_en", "otp_pwr_mode", "otp_web_cpu",
                 "otp_rstb_cpu", "otp_seltm_cpu", "otp_readen_cpu", "otp_pgmen_cpu", "otp_dle_cpu",
                 "otp_din_cpu", "otp_cpumpen_cpu", "otp_cle_cpu", "otp_ceb_cpu", "otp_adr_cpu", "otp_dat_cpu",
                 "blank_finish", "bisr_finish", "key_cmp_result", "data_acp_flag", "otp_wrg_adr_flag"):
        board.otp.write(o.OFFSET[name], 4, 0, 0)
    assert not board.warnings
