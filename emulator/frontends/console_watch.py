"""--expect and --fail-on: the firmware's console as a test's pass condition, as Wokwi's CLI
(`--expect-text`, `--fail-text`) and Renode's UART keywords offer.

Texts are matched in the console stream as it is printed, so a prompt that ends no line is
found too, and a text may span lines. Regular expressions are matched against each
completed line (without its line ending), so that `frame \\d+$` waits for the whole number.
Expected patterns are taken in order: each is looked for only after the previous one's
match. A failure pattern counts wherever it appears.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Callable

from ..errors import BoardStop, ConsoleExpectationsMet, ConsoleFailText
from ..vtime import Time, ms, to_seconds


@dataclass(frozen=True)
class ConsolePattern:
    """One --expect/--fail-on pattern: a literal text, or a regular expression (`regex`)."""
    text: str
    regex: re.Pattern[str] | None = None

    @staticmethod
    def literal(text: str) -> "ConsolePattern":
        if not text:
            raise ValueError("an empty text would match before anything is printed")
        return ConsolePattern(text)

    @staticmethod
    def expression(text: str) -> "ConsolePattern":
        try:
            return ConsolePattern(text, re.compile(text))
        except re.error as error:
            raise ValueError(f"{text!r} is not a regular expression ({error})") from None

    @property
    def label(self) -> str:
        return f"/{self.text}/" if self.regex is not None else repr(self.text)


@dataclass
class Match:
    pattern: ConsolePattern
    virtual_time: Time
    line: str            # the console line it was found in (as far as it had been printed)


class ConsoleWatch:
    """Follows the console byte by byte; ends the run through `stop` when every expected
    pattern has been printed (ConsoleExpectationsMet) or a failure pattern has
    (ConsoleFailText)."""

    def __init__(self, expected: list[ConsolePattern], failures: list[ConsolePattern]) -> None:
        self.expected = expected
        self.failures = failures
        self.matches: list[Match] = []
        self.failure: Match | None = None
        self._text: list[str] = []          # the console so far, one character per byte
        self._after = 0                     # where the next expected pattern may begin
        self._line_start = 0
        self._stop: Callable[[BoardStop], None] = lambda error: None

    @property
    def active(self) -> bool:
        return bool(self.expected or self.failures)

    @property
    def next_expected(self) -> ConsolePattern | None:
        return self.expected[len(self.matches)] if len(self.matches) < len(self.expected) else None

    @property
    def all_met(self) -> bool:
        return self.next_expected is None

    def attach(self, stop: Callable[[BoardStop], None]) -> None:
        """`stop(error)` ends the run after the current instruction (Board.stop_run)."""
        self._stop = stop

    def byte(self, byte: int, at: Time) -> None:
        """A byte the console received (its stop bit out at virtual time `at`)."""
        if not self.active or self.failure is not None:
            return
        self._text.append(chr(byte) if byte != 13 else "")
        end = len(self._text)
        if byte == 10:
            line = "".join(self._text[self._line_start:end - 1])
            self._check_line(line, self._line_start, at)
            self._line_start = end
        else:
            self._check_tail(at)

    def _current_line(self) -> str:
        return "".join(self._text[self._line_start:])

    def _ends_with(self, text: str, start_min: int) -> bool:
        start = len(self._text) - len(text)
        return start >= start_min and "".join(self._text[start:]) == text

    def _check_tail(self, at: Time) -> None:
        for pattern in self.failures:
            if pattern.regex is None and self._ends_with(pattern.text, 0):
                return self._failed(pattern, at, self._current_line())
        pattern = self.next_expected
        if pattern is not None and pattern.regex is None and self._ends_with(pattern.text, self._after):
            self._after = len(self._text)
            self._met(pattern, at, self._current_line())

    def _check_line(self, line: str, line_start: int, at: Time) -> None:
        self._check_tail(at)        # a literal text that ends with the line ending
        if self.failure is not None:
            return
        for pattern in self.failures:
            if pattern.regex is not None and pattern.regex.search(line):
                return self._failed(pattern, at, line)
        pattern = self.next_expected
        if pattern is not None and pattern.regex is not None:
            # within the line, only after the previous expected pattern's match
            skip = max(0, self._after - line_start)
            if skip <= len(line) and pattern.regex.search(line, skip):
                self._after = len(self._text)
                self._met(pattern, at, line)

    def _met(self, pattern: ConsolePattern, at: Time, line: str) -> None:
        self.matches.append(Match(pattern, at, line))
        if self.all_met and self.expected:
            labels = ", ".join(p.label for p in self.expected)
            self._stop(ConsoleExpectationsMet(f"the console printed every expected text ({labels}); the last "
                                              f"at {ms(at)} of virtual time"))

    def _failed(self, pattern: ConsolePattern, at: Time, line: str) -> None:
        self.failure = Match(pattern, at, line)
        self._stop(ConsoleFailText(f"--fail-on {pattern.label}: the console printed it at {ms(at)} "
                                   f"of virtual time, in the line {line!r}"))

    def unmet_message(self, ended: str) -> str:
        """Why the run failed its --expect list: which pattern was never printed."""
        pattern = self.next_expected
        done = len(self.matches)
        return (f"--expect {pattern.label}: {ended}, the console had not printed it ({done} of "
                f"{len(self.expected)} expected texts printed before)")

    def summary(self) -> dict:
        """run.json's record of the patterns and where each matched."""
        def entry(match: Match) -> dict:
            return {"pattern": match.pattern.label, "virtual_time_s": to_seconds(match.virtual_time), "line": match.line}
        return {"expect": [p.label for p in self.expected], "fail_on": [p.label for p in self.failures],
                "expect_matched": [entry(m) for m in self.matches],
                "fail_on_matched": entry(self.failure) if self.failure else None}
