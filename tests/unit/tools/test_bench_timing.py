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
    assert figures["rocket_runs"] == [{"timing": "rocket", "host_time_s": 8.0, "host_ms_per_frame": 5.5}]


def test_the_real_time_factor_is_taken_after_loading_in_wall_and_cpu_time():
    from emulator.board.scheduler import FrameRecord
    frames = [FrameRecord(n, virtual_time_s=0.150 + 0.010 * n, instructions=[0, 0], instructions_total=[0, 0],
                          host_time_s=2.0 + 0.008 * n, host_cpu_s=1.9 + 0.0125 * n) for n in range(5)]
    figures = bench.real_time_figures(frames)
    # 40 ms of virtual time in 32 ms of wall time and 50 ms of CPU time: the loading (frame 0) left out
    assert abs(figures["real_time_factor"] - 1.25) < 1e-9 and abs(figures["real_time_factor_cpu"] - 0.8) < 1e-9
    assert abs(figures["host_cpu_ms_per_frame"] - 12.5) < 1e-9


def test_the_fastest_run_counts_in_each_clock():
    runs = [{"real_time_factor": 1.4, "real_time_factor_cpu": 1.2, "host_ms_per_frame": 5.4,
             "host_cpu_ms_per_frame": 6.3, "virtual_ms_per_frame": 7.6},
            {"real_time_factor": 1.3, "real_time_factor_cpu": 1.3, "host_ms_per_frame": 5.8,
             "host_cpu_ms_per_frame": 5.8, "virtual_ms_per_frame": 7.6}]
    best = bench.fastest(runs)
    assert (best["real_time_factor"], best["real_time_factor_cpu"], best["runs"]) == (1.4, 1.3, 2)
    assert (best["host_ms_per_frame"], best["host_cpu_ms_per_frame"]) == (5.4, 5.8)
