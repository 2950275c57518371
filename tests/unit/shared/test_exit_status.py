"""One table of exit statuses for every command (k210_common/exit_status.py): the commands
return its numbers, their --help lists what they return, and the tables of docs/reference/ are the ones
the code makes (tools/exit_status_tables.py)."""
from __future__ import annotations

import pytest

from k210_common.exit_status import BY_CODE, TABLE, help_epilog, markdown_table
from tools.exit_status_tables import READMES, command_details, rewritten


def test_the_table_is_one_number_and_one_name_a_status():
    codes = [status.code for status in TABLE]
    numbered = [code for code in codes if code < 128]
    assert numbered == list(range(len(numbered)))
    # a run ended by a signal: 128 + its number, as shells report it
    assert [code for code in codes if code >= 128] == [128 + 2, 128 + 15]
    names = [status.name for status in TABLE]
    assert len(set(names)) == len(names)
    # the board model's numbers, in use in scripts and CI, stay as they were
    assert names[:13] == ["ok", "internal", "usage", "trap", "hang", "unmodelled", "bad-input", "misuse",
                          "firmware-error", "golden-mismatch", "stray-write", "fail-on", "expect-unmet"]


@pytest.mark.parametrize("command", ["emulator", "sdcard_image", "reference", "flash", "regen_goldens"])
def test_each_command_returns_only_statuses_of_the_table(command):
    details = command_details()[command]
    assert set(details) <= set(BY_CODE)
    assert 0 in details and 2 in details, "every command succeeds or refuses its command line"
    assert all(text.strip() for text in details.values())


def test_the_readme_tables_are_the_codes():
    commands = command_details()
    found = []
    for readme in READMES:
        text = readme.read_text()
        new, keys = rewritten(text, commands)
        assert new == text, (f"{readme}: an exit-status table differs from the code; "
                             f"python -m tools.exit_status_tables rewrites it")
        found += keys
    assert sorted(found) == ["all", "emulator", "reference", "sdcard_image"]


def test_help_and_readme_rows_come_from_one_mapping():
    details = {0: "done, with `--option`", 6: "a file cannot be used"}
    assert help_epilog(details) == "exit status:\n  0  ok: done, with --option\n  6  bad-input: a file cannot be used\n"
    assert markdown_table(details).splitlines()[2:] == ["| 0 | ok | done, with `--option` |",
                                                        "| 6 | bad-input | a file cannot be used |"]
    with pytest.raises(ValueError, match="not in"):
        help_epilog({99: "no such status"})
