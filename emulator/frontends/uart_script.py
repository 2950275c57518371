"""--uart-script FILE: a conversation with the firmware's console, as Renode's "Wait For Line On
Uart" / "Write Line To Uart" keywords and Wokwi's automation scenarios hold one.

One step a line, taken in order:

    expect TEXT        wait until the console has printed TEXT (anywhere in the stream after what
                       the previous expect matched, so also during an earlier sleep or send; a
                       prompt that ends no line is found too)
    expect-re REGEX    likewise, until a console line completed after the previous match matches
                       REGEX (the line without its line ending)
    send TEXT          send TEXT to the receiver routed from pad 4, as --uart-input does
    sleep SECONDS      let SECONDS of virtual time pass
    timeout SECONDS    how long each later expect may wait, in virtual time (10 s unless set)

TEXT runs to the line's end, leading spaces after the keyword's one space kept; `\\r`, `\\n`, `\\t`,
`\\\\` and `\\xNN` stand for those bytes. Console bytes are characters 0-255 (latin-1), so TEXT is
too: a character beyond is bad input. Blank lines and lines starting with `#` are skipped. An
expect not met in its time fails the run (the expectation status, 12), naming the script's line;
the run ends with status 0 once the last step is done.
"""
from __future__ import annotations

import re
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..errors import BadInput, BoardStop, ConsoleExpectationsMet, ConsoleExpectationUnmet
from ..vtime import Time, from_seconds, ms, to_seconds

DEFAULT_TIMEOUT_S = 10.0
MAX_KEPT = 1 << 16          # console characters and lines kept while a step waits (the oldest go)
KEYWORDS = ("expect", "expect-re", "send", "sleep", "timeout")
_ESCAPE = re.compile(r"\\(x[0-9A-Fa-f]{2}|.|$)")
_ESCAPES = {"r": "\r", "n": "\n", "t": "\t", "\\": "\\"}


@dataclass(frozen=True)
class Step:
    line: int                      # the line of the script it came from
    keyword: str                   # expect, expect-re, send, sleep
    text: str = ""                 # expect's text, send's bytes (escapes resolved), expect-re's source
    regex: re.Pattern[str] | None = None
    seconds: float = 0.0           # sleep's time, expect's time limit

    def describe(self) -> str:
        if self.keyword == "sleep":
            return f"sleep {self.seconds:g}"
        return f"{self.keyword} {self.text!r}"


def _unescape(text: str, where: str) -> str:
    def one(match: re.Match[str]) -> str:
        code = match.group(1)
        if len(code) == 3:
            return chr(int(code[1:], 16))
        if code not in _ESCAPES:
            raise BadInput(f"{where}: an escape other than \\r, \\n, \\t, \\\\ or \\xNN")
        return _ESCAPES[code]
    return _ESCAPE.sub(one, text)


def parse(text: str, name: str) -> list[Step]:
    """The script's steps; BadInput naming the line for anything it cannot take."""
    steps: list[Step] = []
    timeout = DEFAULT_TIMEOUT_S
    for number, raw in enumerate(text.splitlines(), 1):
        if not raw.strip() or raw.lstrip().startswith("#"):
            continue
        keyword, _, rest = raw.lstrip().partition(" ")
        where = f"--uart-script {name}:{number}"
        if keyword not in KEYWORDS:
            raise BadInput(f"{where}: {keyword!r} is not one of {', '.join(KEYWORDS)}")
        if keyword in ("sleep", "timeout"):
            try:
                seconds = float(rest)
            except ValueError:
                seconds = -1.0
            if not seconds >= 0 or seconds == float("inf"):
                raise BadInput(f"{where}: {keyword} needs a number of seconds (0 or more), not {rest.strip()!r}")
            if keyword == "timeout":
                timeout = seconds
            else:
                steps.append(Step(number, keyword, seconds=seconds))
            continue
        if not rest:
            raise BadInput(f"{where}: {keyword} needs a text")
        if keyword == "expect-re":
            try:
                steps.append(Step(number, keyword, rest, re.compile(rest), timeout))
            except re.error as error:
                raise BadInput(f"{where}: {rest!r} is not a regular expression ({error})") from None
            continue
        text = _unescape(rest, where)
        try:
            text.encode("latin-1")
        except UnicodeEncodeError:
            raise BadInput(f"{where}: {text!r} holds a character beyond 0xFF (console bytes are latin-1 "
                           f"characters; write such bytes as \\xNN)") from None
        steps.append(Step(number, keyword, text, seconds=timeout))
    return steps


class UartScript:
    """The script as it runs: the bytes its sends queue for the receiver (the SerialInput port,
    devices/ports.py) and the console it follows. The board calls back at the times it asks for
    (Board.grab_at), between turns."""

    def __init__(self, path: Path, steps: list[Step]) -> None:
        self.path = path
        self.steps = steps
        self.done: list[tuple[Step, Time]] = []       # each step and when it was done
        self.total = 0                                  # bytes sent
        self._queue: deque[int] = deque()
        self._index = 0
        self._started = 0                               # when the step under way began
        self._text = ""                                 # the console since the last match
        self._lines: list[str] = []                     # the lines completed since the last match
        self._line: list[str] = []                      # the console line under way
        self._board = None
        self._stop: Callable[[BoardStop], None] = lambda error: None

    @staticmethod
    def open(source: str) -> "UartScript":
        path = Path(source)
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as error:
            raise BadInput(f"--uart-script {source}: cannot read it ({getattr(error, 'strerror', None) or error})") from None
        return UartScript(path, parse(text, source))

    def attach(self, board) -> None:
        """Starts the script at the board's time 0; the run ends through board.stop_run."""
        self._board = board
        self._stop = board.stop_run
        self._advance(0)

    @property
    def step(self) -> Step | None:
        return self.steps[self._index] if self._index < len(self.steps) else None

    # --- the receiver's side (SerialInput) ------------------------------------------------------

    # Bytes are queued only at a console byte or at a time the board calls back at, both of which
    # the UARTs look at again afterwards: nothing comes from outside in between.
    may_grow = False

    def has_byte(self, virtual_now: Time) -> bool:
        return bool(self._queue)

    def pop(self) -> int:
        return self._queue.popleft()

    def put_back(self, byte: int) -> None:
        self._queue.appendleft(byte)

    # --- the console's side -----------------------------------------------------------------------

    def console_byte(self, byte: int, at: Time) -> None:
        if self.step is None:
            return
        char = chr(byte)
        self._text = (self._text + char)[-MAX_KEPT:]
        if char == "\n":
            self._lines = (self._lines + ["".join(self._line).rstrip("\r")])[-MAX_KEPT:]
            self._line.clear()
        else:
            self._line.append(char)
        if self._index < len(self.steps) and self.steps[self._index].keyword.startswith("expect"):
            self._look(at)

    def _look(self, at: Time) -> None:
        """The expect under way is met if what the console printed since the last match holds it:
        the text and lines after the match are kept for the next expect."""
        step = self.step
        if step.keyword == "expect":
            found = self._text.find(step.text)
            if found < 0:
                return
            self._text = self._text[found + len(step.text):]
            self._lines = []
            self._line = list(self._text.rsplit("\n", 1)[-1]) if "\n" in self._text else list(self._text)
        else:
            matched = next((n for n, line in enumerate(self._lines) if step.regex.search(line)), None)
            if matched is None:
                return
            self._lines = self._lines[matched + 1:]
            # the text after the matched line's end
            ends = [n for n, char in enumerate(self._text) if char == "\n"]
            self._text = self._text[ends[-1 - len(self._lines)] + 1:] if len(ends) > len(self._lines) else self._text
        self._finish(at)

    # --- stepping ---------------------------------------------------------------------------------

    def _finish(self, at: Time) -> None:
        self.done.append((self.steps[self._index], at))
        self._index += 1
        self._advance(at)

    def _advance(self, now: Time) -> None:
        """Starts the steps that can start at `now`: sends go out at once, a sleep or an expect asks
        the board to call back when its time is up."""
        while True:
            step = self.step
            if step is None:
                self._stop(ConsoleExpectationsMet(f"the --uart-script {self.path} ran to its end ({len(self.steps)} "
                                                  f"steps, the last done at {ms(now)} of virtual time)"))
                return
            self._started = now
            if step.keyword == "send":
                self._queue.extend(step.text.encode("latin-1"))
                self.total += len(step.text)
                self.done.append((step, now))
                self._index += 1
                continue
            index, end = self._index, now + from_seconds(step.seconds)
            if step.keyword == "sleep":
                self._board.grab_at(end, lambda board: self._slept(index, end))
                return
            self._board.grab_at(end, lambda board: self._expired(index))
            self._look(now)          # printed already, during a sleep or a send
            return

    def _slept(self, index: int, at: Time) -> None:
        if self._index == index:
            self._finish(at)
            if self._queue:
                # (called between turns) the receiver takes the first byte a send queued now, as it
                # would at a turn's start: with every hart asleep no turn would come to start it
                self._board.advance_devices(at)

    def _expired(self, index: int) -> None:
        if self._index != index:
            return
        step = self.step
        since = "the previous step" if index else "reset"
        raise ConsoleExpectationUnmet(f"--uart-script {self.path}:{step.line}: {step.describe()}: the console did not "
                                      f"print it within {step.seconds:g} s of virtual time after {since}")

    def summary(self) -> dict:
        """run.json's record: each step done and when; the step the run ended in."""
        step = self.step
        return {"file": str(self.path), "steps": len(self.steps), "sent": self.total,
                "done": [{"line": s.line, "step": s.describe(), "virtual_time_s": to_seconds(at)} for s, at in self.done],
                "waiting_at": None if step is None else {"line": step.line, "step": step.describe()}}
