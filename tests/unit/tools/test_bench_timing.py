"""tools/bench.py timing_figures: what the cycle model (or the caches) cost the host, compared a frame
after loading, fastest to fastest over alternating runs; not the whole run's host time, which the
timing changes through the loading's virtual length."""
from __future__ import annotations

from pathlib import Path

from tools import bench


def test_the_cycle_model_s_host_cost_is_compared_a_frame_after_loading(monkeypatch):
    # ipc1's runs: shorter frames on the host, but a loading that takes longer in host time
    runs = iter([{"timing": "ipc1", "host_time_s": 9.0, "host_ms_per_frame": 4.0},
                 {"timing": "rocket", "host_time_s": 8.0, "host_ms_per_frame": 5.5},
                 {"timing": "ipc1", "host_time_s": 9.5, "host_ms_per_frame": 4.4}])
    calls = []

    def fake(firmware, card, frames, timing="rocket", **_):
        calls.append(timing)
        return next(runs)

    monkeypatch.setattr(bench, "firmware_figures", fake)
    rocket = {"timing": "rocket", "host_time_s": 8.5, "host_ms_per_frame": 5.0}
    figures = bench.timing_figures(Path("fw.elf"), Path("card.img"), 60, rocket, rounds=2)
    assert calls == ["ipc1", "rocket", "ipc1"]                  # alternating, after the given rocket run
    assert figures["host_cost_of_cycle_model"] == 5.0 / 4.0     # the fastest frames of each
    assert figures["host_ms_per_frame"] == 4.0 and figures["rounds"] == 2
