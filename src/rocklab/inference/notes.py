"""The marks and words of the notes under a table: values given without an interval, counts of units."""

from __future__ import annotations

#: Marks of the values given without an interval in markdown, one per distinct note.
NOTE_MARKS = "†‡§¶"


def counted(n: int, noun: str) -> str:
    """``n`` and ``noun`` ("test", "series"), plural but for one: "1 test", "154 tests", "1 series"."""
    return f"{n} {noun}{'' if n == 1 or noun.endswith('s') else 's'}"


def note_mark(notes: dict[str, str], note: str) -> str:
    """The mark of ``note`` in ``notes`` (note -> mark, in order of first use), added if new."""
    return notes.setdefault(note, NOTE_MARKS[len(notes) % len(NOTE_MARKS)])


def note_lines(notes: dict[str, str]) -> list[str]:
    """The lines under a markdown table that explain its marks (:func:`note_mark`)."""
    return [f"{mark} {note}" for note, mark in notes.items()]
