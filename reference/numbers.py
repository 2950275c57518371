"""Decimal numbers as firmware/parse.S (`parse_number`) reads them, for the host's readers of
.obj and scene.ini (reference/obj.py, reference/scene.py, and through them the card builder).

Grammar: ``[+|-] (digits [. digits] | . digits) [(e|E) [+|-] digits]``, ASCII digits only, the
whole token (the readers split at spaces and tabs).

The value is the double parse.S computes, not Python's correctly rounded float(): the firmware
decides range ("number out of range", fov, ambient, ...) on that double rounded to single
precision, and float() rounds differently in two cases, so a host deciding on float() accepted
numbers the firmware refuses and the reverse:

- more than 19 significant digits: parse.S keeps the first 19 (it takes digits while its integer
  is below PARSE_MANTISSA_LIMIT = 10^18) and drops the rest, without rounding;
- a long mantissa or an exponent beyond 22: parse.S rounds the integer to double, then rounds
  again at each multiplication or division by a power of ten (10^22 at a time while the exponent
  is beyond PARSE_POW10_MAX = 22), so the result may be a unit in the last place away from
  float()'s, and then round to a different single.

E.g. ``3.402823567797336323e38`` is the largest single by float() and infinite by parse.S;
``3.40282356779733644e38`` the reverse. The value differs from the number written in the file
by a few units in the last place of double precision at most, which the float64 reference
renderer cannot show; its single-precision rounding (`single`) is what the firmware stores.

Every step below is one IEEE double operation with round-to-nearest-even, as the K210's FPU
performs it with fcsr = 0 (firmware_calls.py), so the emulation is bit-exact.
"""
from __future__ import annotations

import re

import numpy as np

# sign, integer digits, fraction digits, exponent sign, exponent digits; the lookahead asks
# for at least one digit before or just after the point
NUMBER = re.compile(r"([+-]?)(?=\.?[0-9])([0-9]*)(?:\.([0-9]*))?(?:[eE]([+-]?)([0-9]+))?")
MANTISSA_DIGITS = 19             # parse.S keeps digits while its integer is below 10^18
EXPONENT_DIGITS = 6              # parse.S PARSE_EXPONENT_CAP = 100000: digits are taken while
                                 # the exponent is below it, so at most 6 significant ones count
POW10_MAX = 22                   # parse.S PARSE_POW10_MAX: 10^22 is the largest exact in double
POW10 = [float(10 ** k) for k in range(POW10_MAX + 1)]
# The smallest magnitude that rounds to infinity in single precision: halfway between the
# largest single, 2^128 - 2^104, and 2^128 (the tie goes to the even one, 2^128).
SINGLE_OVERFLOW = 2.0 ** 128 - 2.0 ** 103


def parse_number(token: str) -> float | None:
    """The double parse.S computes for a whole token, or None when the token is not a number."""
    match = NUMBER.fullmatch(token)
    if match is None:
        return None
    sign, whole, fraction, exponent_sign, exponent_digits = match.groups()
    digits = whole + (fraction or "")
    significant = digits.lstrip("0")
    kept = significant[:MANTISSA_DIGITS]
    # every integer digit not kept raises the exponent by one, every fraction digit kept
    # (leading zeros included) lowers it by one: both come to this
    exponent = len(whole) - (len(digits) - len(significant)) - len(kept)
    if exponent_digits:
        magnitude = int(exponent_digits.lstrip("0")[:EXPONENT_DIGITS] or "0")
        exponent += -magnitude if exponent_sign == "-" else magnitude
    value = _scaled(int(kept or "0"), exponent)
    return -value if sign == "-" else value


def _scaled(mantissa: int, exponent: int) -> float:
    """mantissa x 10^exponent as parse.S computes it: the integer rounded to double, then
    multiplied (or divided) by 10^22 while the exponent is beyond 22, then by 10^exponent."""
    value = float(mantissa)                  # CPython rounds an int to nearest even, as fcvt.d.lu
    if value == 0.0:
        return value
    if exponent >= 0:
        # stopping at infinity only saves steps: parse.S's further products stay infinite
        while exponent > POW10_MAX and value != float("inf"):
            value *= POW10[POW10_MAX]
            exponent -= POW10_MAX
        return value * POW10[min(exponent, POW10_MAX)]
    exponent = -exponent
    while exponent > POW10_MAX and value != 0.0:          # (and zero stays zero)
        value /= POW10[POW10_MAX]
        exponent -= POW10_MAX
    return value / POW10[min(exponent, POW10_MAX)]


def single(value: float) -> float:
    """value rounded to single precision (to nearest even) as the firmware stores it
    (fcvt.s.d); infinite when it overflows."""
    with np.errstate(over="ignore"):
        return float(np.float32(value))


def finite_single(value: float) -> bool:
    """Whether value stays finite in single precision (`single` without numpy's cost per number:
    a model has hundreds of thousands)."""
    return abs(value) < SINGLE_OVERFLOW
