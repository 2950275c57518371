"""The SSI controllers' frames on the wire (spi.py): how long a frame takes (FrameClock), and a
train of frames sent back to back (FrameTrain), each edge reckoned from the train's start in
whole picoseconds (vtime.py), so that no edge depends on how often the controller was advanced."""
from __future__ import annotations

from dataclasses import dataclass, field as dc_field

import numpy as np

from ..vtime import Time, cycles_in, cycles_time


@dataclass(frozen=True)
class FrameClock:
    """How long a frame takes on the wire: `ticks` ticks of a clock at `hz` (whole numbers, so that a
    train's edges are exact: a frame of b bits on n lanes at baudr d from a source at f Hz takes
    b / n x d / f s, that is b x d ticks at n x f Hz)."""

    ticks: int
    hz: int


@dataclass
class FrameTrain:
    """Frames going out back to back: frame i starts at edge(i), i frames' time after the train's
    start (each edge reckoned from the start, so that it does not depend on how often advance() ran)."""

    start: Time
    clock: FrameClock
    bits: int
    frames: list = dc_field(default_factory=list)  # numpy chunks of uint32 frames, in order
    count: int = 0          # frames queued in this train
    delivered: int = 0      # frames already handed to the device

    def edge(self, i: int) -> Time:
        """When frame i starts (frame i - 1 has arrived): rounded up to a whole picosecond."""
        return self.start + cycles_time(i * self.clock.ticks, self.clock.hz)

    def edges_passed(self, now: Time) -> int:
        """How many frames' time has wholly passed since the start by `now` (>= start), however many
        frames the train has: the last i with edge(i) <= now."""
        return cycles_in(now - self.start, self.clock.hz) // self.clock.ticks

    def end(self) -> Time:
        return self.edge(self.count)

    def started(self, now: Time) -> int:
        if now < self.start:
            return 0
        return min(self.count, self.edges_passed(now) + 1)

    def finished(self, now: Time) -> int:
        if now < self.start:
            return 0
        return min(self.count, self.edges_passed(now))

    def take(self, n: int) -> np.ndarray:
        """Removes and returns the next n undelivered frames."""
        out, need = [], n
        while need:
            chunk = self.frames[0]
            if len(chunk) <= need:
                out.append(chunk)
                need -= len(chunk)
                self.frames.pop(0)
            else:
                out.append(chunk[:need])
                self.frames[0] = chunk[need:]
                need = 0
        self.delivered += n
        return np.concatenate(out) if len(out) > 1 else out[0]
