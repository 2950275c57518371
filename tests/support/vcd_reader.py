"""A small reader of the Value Change Dumps `run --vcd` writes (emulator/frontends/vcd.py), our own
rather than the writer's, for the tests that check the pins over time (unit/frontends/test_vcd.py,
end_to_end/test_c_firmware.py)."""
from __future__ import annotations


def read_vcd(text: str) -> tuple[str, dict[str, list[tuple[int, str]]]]:
    """(timescale, signal -> [(time, value)]) of a VCD's one-bit wires."""
    header, _, body = text.partition("$enddefinitions $end\n")
    timescale = header.split("$timescale", 1)[1].split("$end", 1)[0].strip()
    names = {}
    for line in header.splitlines():
        if line.startswith("$var "):
            _, kind, width, code, name, _ = line.split()
            assert (kind, width) == ("wire", "1")
            names[code] = name
    changes: dict[str, list[tuple[int, str]]] = {name: [] for name in names.values()}
    now = None
    for line in body.splitlines():
        if line.startswith("#"):
            tick = int(line[1:])
            assert now is None or tick >= now, "time goes backwards"
            now = tick
        else:
            changes[names[line[1:]]].append((now, line[0]))
    return timescale, changes
