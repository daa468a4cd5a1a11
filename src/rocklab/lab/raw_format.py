"""What every file of the lab's raw format shares: its error, and the names it may give.

Every problem of a campaign file is a :class:`RawFormatError` naming the
file, the row (1-based line number, header and comment lines included) and
the problem, so that a lab technician can open the file at that line.  The
ids of a campaign name results files (:func:`check_identifier`) and its
tables name files of the campaign folder (:func:`campaign_file`): both are
checked at the door, before anything is read.  The tables are read by
:mod:`rocklab.lab.campaign`, the records by :mod:`rocklab.lab.records`
(``docs/raw-format.md``).
"""

from __future__ import annotations

import os
import re
from functools import cache, lru_cache
from pathlib import Path

#: Longest id (test_id, specimen) that names a results file.
ID_MAX_LENGTH = 64
#: Ids that can name a results file: letters, digits and . _ -, starting with a letter or a digit.
SAFE_ID = re.compile(rf"[A-Za-z0-9][A-Za-z0-9._-]{{0,{ID_MAX_LENGTH - 1}}}")
#: Control characters (tab aside) that no table or record may hold.
CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f]")


def holds_any(characters: re.Pattern[str], text: str) -> bool:
    """Whether ``text`` holds any of the single ``characters`` (a pattern of one character class).

    ``characters.search(text)``; an ASCII text (a lab record) is answered by
    deleting every ASCII character outside the class and seeing what is
    left, ten times faster than the search on a record of 100 kB.
    """
    if text.isascii():
        return bool(text.encode("ascii").translate(None, _ascii_outside(characters)))
    return characters.search(text) is not None


@cache
def _ascii_outside(characters: re.Pattern[str]) -> bytes:
    return bytes(c for c in range(128) if not characters.fullmatch(chr(c)))


class RawFormatError(ValueError):
    """A campaign file that does not follow the lab's format.

    Attributes
    ----------
    path : str
        The offending file.
    row : int or None
        1-based line number in that file (None when the whole file is at fault).
    problem : str
        What is wrong, in words.
    """

    def __init__(self, path: str | Path, row: int | None, problem: str) -> None:
        self.path, self.row, self.problem = str(path), row, problem
        where = f"{self.path}:{row}" if row is not None else self.path
        super().__init__(f"{where}: {problem}")


def check_identifier(value: str, what: str) -> str | None:
    """Why ``value`` cannot name a file of the results (None when it can).

    Test ids name the files ``results/tests/<job>/<id>.nc`` and specimen ids the
    series (``<specimen>-2s``) that name logs and figures: only letters,
    digits and ``. _ -``, starting with a letter or a digit, at most
    :data:`ID_MAX_LENGTH` characters, so that no id can climb out of the
    results folder (``../x``), hide a file (``.x``) or break a rule name.
    """
    if not value:
        return f"empty {what}"
    if not SAFE_ID.fullmatch(value):
        return (
            f"{what} {value!r} is not a safe name (letters, digits and . _ - only, starting with a letter or"
            f" digit, at most {ID_MAX_LENGTH} characters)"
        )
    return None


def campaign_file(root: str | Path, relative: str, what: str = "file") -> tuple[Path | None, str | None]:
    """The path of a campaign file named in a table, or why it is refused.

    The name is checked before the file system is touched: an absolute path
    or one that climbs out with ``..`` is refused as written; what is left
    is resolved (symbolic links followed) and refused when it lands outside
    the campaign folder.  Nothing outside the folder is ever opened.

    Parameters
    ----------
    root : path-like
        The campaign folder, resolved (``os.path.realpath``) or not.
    relative : str
        The name as the table gives it.
    what : str
        What the name is, for the message.

    Returns
    -------
    (Path, None) or (None, str)
        The resolved path, or the problem in words.
    """
    if not relative:
        return None, f"empty {what}"
    if "\\" in relative or "\x00" in relative:
        return None, f"{what} {relative!r}: use / between folders, no backslash or NUL"
    if relative.startswith("/") or os.path.normpath(relative).split("/")[0] == "..":
        return None, f"{what} {relative!r} leaves the campaign folder (give a path inside it, relative to it)"
    # strings, not Path objects: this runs once per row of the test log
    root = _real(os.fspath(root))
    path = os.path.realpath(os.path.join(root, relative))
    if not path.startswith(root + os.sep):
        return None, f"{what} {relative!r} leads outside the campaign folder (a symbolic link to {path!r})"
    return Path(path), None


@lru_cache(maxsize=8)
def _real(folder: str) -> str:
    return os.path.realpath(folder)
