"""obj.S reads the model through a window (OBJ_WINDOW_BYTES of heap, given back after each pass)
instead of keeping its text: these tests drive its reader on the board model's CPU
(tests/support/firmware_calls.py), with the text in memory, which obj.S copies into the window sector by
sector exactly as it reads the card. The window's edges fall where its reads end, at multiples of
512 bytes of the file; the first is at OBJ_WINDOW_BYTES. Every way a token can meet that edge (a
keyword, a number, a face corner cut anywhere; a CR whose LF is in the next read; a comment; a
token longer than the whole window) must give the tokens a whole text would, line by line, and
the heap must be as it was once the reader is closed.

obj.S's tokens (its file comment): a line's content ends at LF, at '#', at a CR followed by LF or
by the end of the text, or at the end of the text; tokens are what is between spaces and tabs.
"""
from __future__ import annotations

import struct
from pathlib import Path

import pytest

from firmware_calls import FirmwareCaller

# A model's lines with every kind of token, and the ways lines end (LF, CRLF, a comment, a lone
# CR inside a token, blanks and tabs around tokens).
BODY = (b"v 0.125 -2.5e-1 3\r\n"
        b"vt\t0.5 0.25 # uv\n"
        b"vn 0 0 1\n"
        b"usemtl some\tmaterial\r\n"
        b"\n"
        b"  # a comment line\n"
        b"f 1/1/1 12/34/56 -3//-1 7\r8\n"
        b"mtllib x.mtl\r\r\n"
        b"v 1 2 3")                                   # no LF at the end


def expected_tokens(text: bytes) -> list[list[bytes]]:
    """Per line, the tokens obj.S's rules give (see the module docstring)."""
    lines = text.split(b"\n")
    if lines and lines[-1] == b"":
        lines.pop()                                  # a final LF ends the last line
    result = []
    for line in lines:
        if line.endswith(b"\r"):
            line = line[:-1]
        line = line.split(b"#", 1)[0]
        result.append([token for token in line.replace(b"\t", b" ").split(b" ") if token])
    return result


class Reader:
    """obj.S's reader on the board model's CPU, over text in memory."""

    def __init__(self, firmware: Path) -> None:
        self.caller = FirmwareCaller(firmware)
        self.window_bytes = self.caller.symbol("OBJ_WINDOW_BYTES")

    def tokens(self, text: bytes) -> tuple[list[list[bytes]], int, set[int]]:
        """(per line the tokens obj_token returns, the window's largest size, the offsets in the
        text where the window's reads ended). Checks that obj_reader_close gives the heap back
        as it was before obj_reader_open's window."""
        c = self.caller
        c.call("heap_init")
        c.call("heap_alloc", [64])                   # keeps firmware_calls' return wfi out of the window
        address = c.call("heap_alloc", [max(len(text), 1)]).a[0]
        c.write(address, text)
        c.write(c.symbol("scene_model"), struct.pack("<QQQ", address, len(text), 0))
        heap_next = c.symbol("heap_next")
        before = self.u64(heap_next)
        c.call("obj_reader_open", [0])
        reader = c.symbol("obj_reader")
        lines, largest, edges = [], 0, set()
        budget = 50 * len(text) + 100_000

        def step(routine: str) -> tuple[int, ...]:
            result = c.call(routine, budget=budget).a
            edges.add(len(text) - self.u64(reader + c.symbol("RD_LEFT")))
            return result

        while step("obj_more")[0]:
            line = []
            while True:
                start, end = step("obj_token")[:2]
                if start == end:
                    break
                line.append(c.read(start, end - start))
            lines.append(line)
            largest = max(largest, self.u64(reader + c.symbol("RD_CAP")))
            step("obj_next_line")
        c.call("obj_reader_close")
        assert self.u64(heap_next) == before, "the window was not given back"
        return lines, largest, edges - {0, len(text)}

    def u64(self, address: int) -> int:
        return struct.unpack("<Q", self.caller.read(address, 8))[0]


@pytest.fixture(scope="module")
def reader(firmware) -> Reader:
    return Reader(firmware)


def at_offset(start: int, body: bytes) -> bytes:
    """body preceded by one comment line, so that it starts `start` bytes into the file."""
    assert start >= 2
    return b"#" + b"x" * (start - 2) + b"\n" + body


def test_every_cut_of_a_line_at_the_window_edge(reader):
    """The body starts 0 .. len(BODY) bytes before the first edge: each of its bytes is the last
    one of the first read in one of these texts."""
    edge = reader.window_bytes
    for cut in range(len(BODY) + 1):
        text = at_offset(edge - cut, BODY)
        lines, largest, edges = reader.tokens(text)
        assert lines == expected_tokens(text), f"body cut after {cut} bytes"
        assert largest == edge and edges == ({edge} if cut < len(BODY) else set()), (cut, largest, edges)


def test_later_edges_after_a_carried_token(reader):
    """After a refill that carried part of a token, the next edge is nearer (whole sectors after
    the carried bytes): the body's bytes meet that edge too."""
    edge = reader.window_bytes
    carried = b"v 1234567.25 0 0\n"                   # cut at the first edge, 9 bytes carried
    first = at_offset(edge - 9, carried)
    second_edge = 2 * edge - 512                      # 31 sectors after the 9 carried bytes
    for cut in range(0, len(BODY) + 1, 3):
        gap = second_edge - len(first) - cut
        text = first + b"#" + b"y" * (gap - 2) + b"\n" + BODY
        lines, _, edges = reader.tokens(text)
        assert lines == expected_tokens(text), f"body cut after {cut} bytes"
        assert edges == {edge, second_edge}, (cut, edges)


def test_a_cr_at_the_edge_with_its_lf_in_the_next_read(reader):
    """CR as the window's last byte: whether it ends the line depends on the next read."""
    edge = reader.window_bytes
    for body in (b"v 1 2 3\r\nf 1 2 3\n", b"v 1 2 3\r4\n", b"f 1 2\r\r\n", b"v 1 2 3 \r\n"):
        cr = body.index(b"\r")
        text = at_offset(edge - cr - 1, body)
        assert text[edge - 1:edge] == b"\r"
        lines, _, edges = reader.tokens(text)
        assert lines == expected_tokens(text) and edges == {edge}, (body, edges)


def test_a_cr_at_the_end_of_the_text_ends_the_line(reader):
    for text in (b"f 1 2 3\r", b"f 1 2 3\r\r", b"v 1\r2", b"", b"\n", b"\r\n", b"#", b"   "):
        lines, _, _ = reader.tokens(text)
        assert lines == expected_tokens(text), text


def test_a_word_longer_than_the_window_grows_it(reader):
    """A token of 2.5 windows: the window grows by OBJ_WINDOW_BYTES at a time while the token
    fills it, the token comes out whole, and everything is given back at the end."""
    edge = reader.window_bytes
    word = b"1." + b"0" * (edge * 5 // 2) + b"1"
    text = b"v " + word + b" 2 3\nf 1 2 3\n"
    lines, largest, _ = reader.tokens(text)
    assert lines == [[b"v", word, b"2", b"3"], [b"f", b"1", b"2", b"3"]]
    assert largest == 3 * edge, largest


def test_a_long_comment_and_a_long_line_of_short_tokens(reader):
    """Neither a comment nor a line needs to fit the window: only a token must."""
    edge = reader.window_bytes
    corner = b"1" * 99 + b"/2 "                       # 102 bytes, cut somewhere at each edge
    text = b"# " + b"c" * (3 * edge) + b"\nf 1 2 " + corner * (edge // 40) + b"\n"
    lines, largest, edges = reader.tokens(text)
    assert lines == expected_tokens(text) and largest == edge, largest
    assert len([e for e in edges if e > text.index(b"\n")]) >= 2, edges     # the face line met edges
