"""Modules of one topic: no module of src/rocklab over :data:`MAX_LINES` lines unless its
docstring says why, on a line that starts with ``Size:`` (issue 28, item 5)."""

from __future__ import annotations

import ast
from pathlib import Path

import rocklab

#: Longest module that needs no reason [lines].
MAX_LINES = 600
#: What starts the docstring line that gives a longer module's reason.
REASON = "Size:"


def size_reason(source):
    """The text after ``Size:`` on a line of the module docstring of ``source`` ('' if none)."""
    doc = ast.get_docstring(ast.parse(source)) or ""
    reasons = [line.strip()[len(REASON) :].strip() for line in doc.splitlines() if line.strip().startswith(REASON)]
    return next((r for r in reasons if r), "")


def unexplained_long_modules(root, max_lines=MAX_LINES):
    """Modules under ``root`` longer than ``max_lines`` with no reason in their docstring, as 'path (n lines)'."""
    out = []
    for path in sorted(Path(root).rglob("*.py")):
        source = path.read_text()
        n = len(source.splitlines())
        if n > max_lines and not size_reason(source):
            out.append(f"{path.relative_to(root)} ({n} lines)")
    return out


def test_no_module_of_rocklab_is_long_without_its_reason():
    assert unexplained_long_modules(Path(rocklab.__file__).parent) == [], (
        f"split these modules by topic, or give the reason on a docstring line starting {REASON!r}"
    )


def test_a_long_module_needs_a_reason_that_says_something(tmp_path):
    body = "x = 1\n" * 10
    (tmp_path / "short.py").write_text('"""Short."""\n' + "x = 1\n")
    (tmp_path / "bare.py").write_text('"""Long, no reason."""\n' + body)
    (tmp_path / "empty.py").write_text('"""Long.\n\nSize:\n"""\n' + body)
    (tmp_path / "in_code.py").write_text('"""Long."""\n# Size: a comment is not the docstring\n' + body)
    (tmp_path / "reasoned.py").write_text('"""Long.\n\nSize: one algorithm, read top to bottom.\n"""\n' + body)
    assert unexplained_long_modules(tmp_path, max_lines=5) == [
        "bare.py (11 lines)",
        "empty.py (14 lines)",
        "in_code.py (12 lines)",
    ]
    assert size_reason((tmp_path / "reasoned.py").read_text()) == "one algorithm, read top to bottom."
