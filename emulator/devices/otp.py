"""OTP (0x5042_0000): the K210's 16 KiB one-time-programmable memory, read as the Kendryte SDK's
first otp.c read it.

The register map and the read protocol come from the standalone SDK's otp.h/otp.c of September
2018 (commits 685084c to 2772ff0; the driver left the SDK after that): 48 32-bit registers, of
which a read uses

| offset | register         | in a read                                                      |
|--------|------------------|----------------------------------------------------------------|
| 0x00   | otp_ceb          | 0 selects the array                                            |
| 0x08   | otp_mode         | 0 reads (2 is a test mode)                                     |
| 0x20   | otp_last_dat     | 1 before the last byte's address                               |
| 0x24   | otp_data         | the byte at the address last written to otp_apb_adr            |
| 0x30   | otp_apb_adr      | a bit address: byte n is at 8 n                                |
| 0x3C   | otp_adr_in_flag  | 1: an address may be written (array selected, read mode)        |
| 0x58   | otp_cle          | 0 for a read                                                   |
| 0x60   | otp_wrg_adr_flag | 1 after an address the array does not give out                 |
| 0x68   | otp_status       | busy, bypass, test flags: 0                                    |
| 0x88   | otp_readen_cpu   | the CPU-driven read (otp_soft_read): 1 puts the byte at        |
| 0xA4   | otp_adr_cpu      | this bit address into                                          |
| 0xA8   | otp_dat_cpu      | this register                                                  |
| 0xAC   | otp_data_rdy     | 1 once the byte of the last address is in otp_data             |

Layout (otp.h): common data below 0x3AD0, system data to 0x3DD0, BISR data, block and function
control at 0x3FD0, wired registers at 0x3FE0, the AES key at 0x3FF0 (never given out: an address
there sets otp_wrg_adr_flag). A chip's OTP holds Kendryte's factory data, which is not public: the
model's reads as blank (every byte 0) unless `--otp FILE` gives its content, and the run log says
so at the first read. Programming, blank checks, BISR and the test modes stop the run (status 5).
"""
from __future__ import annotations

from ..errors import UnmodelledAccess
from ..memory_map import K210_BLOCKS
from ..vtime import Time
from .mmio import Peripheral, Register
from .ports import Ports

SIZE_BYTES = 16 * 1024
KEY_ADDRESS = 0x3FF0
NAMES = ("otp_ceb", "otp_test_mode", "otp_mode", "gb_otp_en", "dat_in_finish", "otp_bisr_fail", "test_step",
         "otp_pwrrdy", "otp_last_dat", "otp_data", "otp_pwr_mode", "otp_in_dat", "otp_apb_adr", "td_result",
         "data_acp_flag", "otp_adr_in_flag", "wr_result", "otp_thershold", "bisr_finish", "key_cmp_result",
         "otp_cmp_key", "cmp_result_rdy", "otp_cle", "data_blk_ctrl", "otp_wrg_adr_flag", "pro_wrong", "otp_status",
         "otp_pro_adr", "blank_finish", "bisr2otp_en", "otp_cpu_ctrl", "otp_web_cpu", "otp_rstb_cpu",
         "otp_seltm_cpu", "otp_readen_cpu", "otp_pgmen_cpu", "otp_dle_cpu", "otp_din_cpu", "otp_cpumpen_cpu",
         "otp_cle_cpu", "otp_ceb_cpu", "otp_adr_cpu", "otp_dat_cpu", "otp_data_rdy", "block_flag_high",
         "block_flag_low", "reg_flag_high", "reg_flag_low")
OFFSET = {name: 4 * n for n, name in enumerate(NAMES)}
CEB, MODE, DATA, APB_ADR, ADR_IN_FLAG = OFFSET["otp_ceb"], OFFSET["otp_mode"], OFFSET["otp_data"], \
    OFFSET["otp_apb_adr"], OFFSET["otp_adr_in_flag"]
CLE, WRG_ADR_FLAG, DATA_RDY = OFFSET["otp_cle"], OFFSET["otp_wrg_adr_flag"], OFFSET["otp_data_rdy"]
READEN_CPU, ADR_CPU, DAT_CPU = OFFSET["otp_readen_cpu"], OFFSET["otp_adr_cpu"], OFFSET["otp_dat_cpu"]
# registers whose reads the hardware answers (the rest read what was written)
STATUS = {OFFSET[n] for n in ("otp_status", "otp_bisr_fail", "pro_wrong", "td_result", "wr_result", "bisr_finish",
                             "blank_finish", "dat_in_finish", "data_acp_flag", "key_cmp_result", "cmp_result_rdy",
                             "block_flag_high", "block_flag_low", "reg_flag_high", "reg_flag_low")}
# writes that start what the model does not have: programming, the test modes, BISR, key compare
UNMODELLED_WHEN_SET = {OFFSET[n]: n for n in ("otp_test_mode", "otp_pgmen_cpu", "otp_din_cpu", "otp_cmp_key",
                                              "bisr2otp_en", "otp_in_dat", "otp_pro_adr")}
_BLOCK = K210_BLOCKS["OTP"]


class Otp(Peripheral):
    NAME = "OTP"
    BASE, SIZE, GATE = _BLOCK.base, _BLOCK.size, _BLOCK.gate
    # every register takes writes (otp_init and the SDK's status handshakes clear several that the
    # hardware sets); reads of the ones the hardware answers are worked out below
    REGISTERS = {OFFSET[name]: Register(name) for name in NAMES}

    def __init__(self, ports: Ports, content: bytes | None = None, source: str = "") -> None:
        """content: the OTP's bytes (at most 16 KiB, the rest 0); None: blank. source: where it came
        from, for the run log."""
        super().__init__(ports)
        self.content = bytes(content or b"").ljust(SIZE_BYTES, b"\0")
        self.source = source
        self._told = False

    def _byte(self, bit_address: int, now: Time) -> int | None:
        """The byte at a bit address; None where the array gives nothing out (the key, past the end)."""
        if not self._told:
            self._told = True
            self.ports.warn(f"OTP: read from {self.source}" if self.source else
                            "OTP: read as blank (every byte 0): a chip's factory data is not public; give its "
                            "content with --otp FILE", now)
        address = bit_address // 8
        if bit_address % 8 or address >= KEY_ADDRESS:
            return None
        return self.content[address]

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        if offset == ADR_IN_FLAG:
            return int(self.values[CEB] == 0 and self.values[MODE] == 0 and self.values[CLE] == 0)
        if offset == DAT_CPU:
            byte = self._byte(self.values[ADR_CPU], now) if self.values[READEN_CPU] & 1 else None
            return 0 if byte is None else byte
        if offset in STATUS:
            return 0
        return self.values[offset]

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        if offset in UNMODELLED_WHEN_SET and value:
            raise UnmodelledAccess(f"OTP.{UNMODELLED_WHEN_SET[offset]} = 0x{value:x}: programming the OTP, its test "
                                   f"modes, BISR and key compare are not modelled (reads are)")
        if offset == MODE and value:
            raise UnmodelledAccess(f"OTP.otp_mode = {value}: only reads (mode 0) are modelled")
        self.values[offset] = value
        if offset == APB_ADR:
            byte = self._byte(value, now)
            self.values[WRG_ADR_FLAG] = int(byte is None)
            self.values[DATA] = 0 if byte is None else byte
            self.values[DATA_RDY] = 1
