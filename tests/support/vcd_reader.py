"""A small reader of the Value Change Dumps `run --vcd` writes (emulator/frontends/vcd.py), our own
rather than the writer's, for the tests that check the pins over time (unit/frontends/test_vcd.py,
end_to_end/test_c_firmware.py)."""
from __future__ import annotations


def parse_vcd(text: str) -> tuple[str, dict[str, str], dict[str, list[tuple[int, str]]]]:
    """(timescale, signal -> its value in the initial $dumpvars, signal -> [(time, value)] of the
    changes after it) of a VCD's one-bit wires."""
    header, _, body = text.partition("$enddefinitions $end\n")
    timescale = header.split("$timescale", 1)[1].split("$end", 1)[0].strip()
    names = {}
    for line in header.splitlines():
        if line.startswith("$var "):
            _, kind, width, code, name, _ = line.split()
            assert (kind, width) == ("wire", "1")
            names[code] = name
    initial: dict[str, str] = {}
    changes: dict[str, list[tuple[int, str]]] = {name: [] for name in names.values()}
    now = None
    dumping = False
    for line in body.splitlines():
        if line == "$dumpvars":
            assert now is not None and not initial and not any(changes.values()), "$dumpvars comes first"
            dumping = True
        elif line == "$end":
            assert dumping
            dumping = False
        elif line.startswith("#"):
            assert not dumping
            tick = int(line[1:])
            assert now is None or tick >= now, "time goes backwards"
            now = tick
        elif dumping:
            initial[names[line[1:]]] = line[0]
        else:
            changes[names[line[1:]]].append((now, line[0]))
    return timescale, initial, changes


def read_vcd(text: str) -> tuple[str, dict[str, list[tuple[int, str]]]]:
    """(timescale, signal -> [(time, value)]) of a VCD's one-bit wires: the changes after the
    initial values."""
    timescale, _, changes = parse_vcd(text)
    return timescale, changes
