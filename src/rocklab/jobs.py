"""A workflow job's life, and what each job left in the results folder.

Snakemake decides what to run from the files it knows: a declared output
that is missing, or older than an input. It cannot see a file inside a
folder output that was deleted, nor any output truncated or replaced after
its job wrote it; and it leaves a missing file alone while the files made
from it are newer. A run that says "nothing to be done" could rest on a
broken file. So every job of the workflow starts with :func:`start` (its
log; a full disk said in one line, :class:`rocklab.disk.NoSpace`) and ends
with :meth:`Job.finish`, which writes its **manifest**: its inputs in the
results folder, and every file of its declared outputs (folders walked)
with its size, modification time and BLAKE2 digest, in
``<results>/.manifests/<first output>.json``.

Before every run the workflow checks the manifests (:func:`damaged`): a
job of which a file is missing, of another size, or of other bytes than
it wrote is damaged. :func:`clear_damage` removes the outputs of each
damaged job and of every job that read them, directly or not (the
manifests' inputs tell): Snakemake then makes them again, as it makes any
missing output, and nothing else.

The manifests are the workflow's bookkeeping, not results: a file's digest
is read again only where its size matches and its time does not.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import logging
import os
import shutil
import sys
from collections.abc import Iterable, Iterator
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Any

from rocklab.disk import NoSpace, StrPath, write_text
from rocklab.io import setup_logging

#: The folder of the manifests, inside the results folder.
MANIFESTS = ".manifests"
#: The lock file in it (:func:`clear_damage`).
LOCK = ".lock"
#: The marker Snakemake writes into a folder output (its time stands for the folder's).
SNAKEMAKE_TIMESTAMP = ".snakemake_timestamp"


def digest(path: StrPath) -> str:
    """The BLAKE2b digest (16 bytes, hex) of a file's bytes."""
    h = hashlib.blake2b(digest_size=16)
    with open(path, "rb") as fh:
        while chunk := fh.read(1 << 20):
            h.update(chunk)
    return h.hexdigest()


def _files(output: Path) -> list[Path]:
    """The files of a declared output: itself, or every file under a folder (Snakemake's marker aside)."""
    if output.is_dir():
        return sorted(p for p in output.rglob("*") if p.is_file() and p.name != SNAKEMAKE_TIMESTAMP)
    return [output] if output.is_file() else []


def manifest_path(results_dir: StrPath, first_output: StrPath) -> Path:
    """Where the manifest of the job whose first declared output is ``first_output`` lies."""
    rel = Path(os.path.relpath(Path(first_output).absolute(), Path(results_dir).absolute()))
    return Path(results_dir) / MANIFESTS / rel.parent / f"{rel.name}.json"


def _relative(paths: Iterable[StrPath], root: Path) -> list[str]:
    """``paths`` inside ``root`` (absolute), relative to it, in order."""
    return [os.path.relpath(Path(p).absolute(), root) for p in paths if root in Path(p).absolute().parents]


def record(outputs: Iterable[StrPath], results_dir: StrPath, inputs: Iterable[StrPath] = ()) -> Path | None:
    """Write the manifest of a job: its declared ``outputs`` and ``inputs`` (paths) in ``results_dir``.

    Returns its path, None for a job with no output in ``results_dir``.
    """
    root = Path(results_dir).absolute()
    outs = _relative(outputs, root)
    if not outs:
        return None
    files = {}
    for output in outs:
        for f in _files(root / output):
            st = f.stat()
            files[os.path.relpath(f, root)] = [st.st_size, st.st_mtime_ns, digest(f)]
    entry = {"outputs": outs, "inputs": _relative(inputs, root), "files": files}
    path = manifest_path(results_dir, root / outs[0])
    write_text(path, json.dumps(entry, indent=0, sort_keys=True) + "\n")
    return path


@dataclass(frozen=True)
class Damage:
    """A job's output that no longer is what the job wrote.

    ``outputs``: the job's declared outputs (relative to the results
    folder); ``file``: the first damaged file; ``problem``: what is wrong
    with it; ``manifest``: the job's manifest.
    """

    outputs: tuple[str, ...]
    file: str
    problem: str
    manifest: Path

    def __str__(self) -> str:
        return f"{self.file}: {self.problem}"


def _problem(path: Path, size: int, mtime_ns: int, blake: str) -> str | None:
    """What is wrong with a recorded file now, None if nothing."""
    try:
        st = path.stat()
        if st.st_size != size:
            return f"{st.st_size} bytes where its job wrote {size}"
        if st.st_mtime_ns != mtime_ns and digest(path) != blake:
            return "changed since its job wrote it"
    except FileNotFoundError:
        return "missing"
    except OSError as exc:
        return f"unreadable ({exc.strerror or exc})"
    return None


def _inside_results(rel: object) -> bool:
    """Whether a path a manifest names stays inside the results folder (relative, no ``..``)."""
    return isinstance(rel, str) and bool(rel) and not Path(rel).is_absolute() and ".." not in Path(rel).parts


def _well_formed(entry: dict[str, Any]) -> bool:
    """Whether a manifest's entry is what :func:`record` writes, every path inside the results folder."""
    files = entry.get("files")
    return (
        isinstance(entry.get("outputs"), list)
        and all(map(_inside_results, entry["outputs"]))
        and isinstance(entry.get("inputs"), list)
        and all(isinstance(i, str) for i in entry["inputs"])
        and isinstance(files, dict)
        and all(
            _inside_results(f)
            and isinstance(r, list)
            and len(r) == 3
            and all(isinstance(x, int) for x in r[:2])
            and isinstance(r[2], str)
            for f, r in files.items()
        )
    )


def _first_output(manifest: Path, root: Path) -> str:
    """The first declared output of a job, from its manifest's path (:func:`manifest_path`)."""
    rel = manifest.relative_to(root / MANIFESTS)
    return (rel.parent / rel.name.removesuffix(".json")).as_posix()


def _manifests(root: Path) -> dict[Path, dict[str, Any] | None]:
    """Every manifest of the results folder ``root``, read (None: unreadable, or not what
    :func:`record` writes: a path it names that leaves the results folder is never followed)."""
    out = {}
    for manifest in sorted((root / MANIFESTS).rglob("*.json")):
        try:
            entry = json.loads(manifest.read_text())
        except (OSError, ValueError):
            entry = None
        out[manifest] = entry if isinstance(entry, dict) and _well_formed(entry) else None
    return out


def damaged(results_dir: StrPath) -> list[Damage]:
    """The jobs of ``results_dir`` with a damaged output (see the module's docstring), by manifest.

    A manifest that cannot be read is the damage of the job of its first output.
    """
    root = Path(results_dir)
    out = []
    for manifest, entry in _manifests(root).items():
        if entry is None:
            rel = manifest.relative_to(root).as_posix()
            out.append(Damage((_first_output(manifest, root),), rel, "unreadable manifest", manifest))
            continue
        bad = next(((f, p) for f, rec in entry["files"].items() if (p := _problem(root / f, *rec))), None)
        if bad is not None:
            out.append(Damage(tuple(entry["outputs"]), bad[0], bad[1], manifest))
    return out


@dataclass(frozen=True)
class Cleared:
    """A damaged job and what :func:`clear_damage` removed for it: ``outputs``, the declared
    outputs of the damaged job and of every job that read them (relative to the results folder)."""

    damage: Damage
    outputs: tuple[str, ...]

    def __str__(self) -> str:
        made = len(self.outputs) - len(self.damage.outputs)
        return f"{self.damage.problem}; its job's outputs and the {made} made from them removed, to be made again"


def _inside(path: str, folders: set[str]) -> bool:
    """Whether ``path`` is one of ``folders`` or lies in one (relative paths)."""
    parts = Path(path).parts
    return any(Path(*parts[:k]).as_posix() in folders for k in range(1, len(parts) + 1))


@contextmanager
def _lock(root: Path, kind: int, wait: bool = True) -> Iterator[bool]:
    """The results folder's lock (``<results>/.manifests/.lock``), shared by running jobs,
    exclusive for :func:`clear_damage`: yields whether it was taken (it is not, without
    waiting, while another holds it; nor where the folder cannot hold the file)."""
    try:
        (root / MANIFESTS).mkdir(parents=True, exist_ok=True)
        fd = os.open(root / MANIFESTS / LOCK, os.O_RDWR | os.O_CREAT, 0o666)
    except OSError:
        yield False
        return
    try:
        fcntl.flock(fd, kind | (0 if wait else fcntl.LOCK_NB))
    except OSError:
        os.close(fd)
        yield False
        return
    try:
        yield True
    finally:
        os.close(fd)


def clear_damage(results_dir: StrPath) -> list[Cleared] | None:
    """Remove the outputs of every damaged job of ``results_dir`` (:func:`damaged`) and of
    every job downstream of it, with their manifests, so that Snakemake makes them again.

    Downstream: a job whose recorded inputs are, or lie in, the removed outputs, and so on.
    None, and nothing removed, while a job of another run holds the folder (its
    outputs may be half-recorded).
    """
    root = Path(results_dir)
    with _lock(root, fcntl.LOCK_EX, wait=False) as held:
        return _clear(root) if held else None


def _clear(root: Path) -> list[Cleared]:
    entries = {m: e for m, e in _manifests(root).items() if e is not None}
    out = []
    for damage in damaged(root):
        if not damage.manifest.exists():
            continue  # downstream of a damage cleared before
        removed = list(damage.outputs)
        cone = {damage.manifest}
        grew = True
        while grew:
            grew = False
            for manifest, entry in entries.items():
                if manifest not in cone and any(_inside(i, set(removed)) for i in entry["inputs"]):
                    cone.add(manifest)
                    removed += entry["outputs"]
                    grew = True
        for rel in removed:
            target = root / rel
            if target.is_dir() and not target.is_symlink():
                shutil.rmtree(target)
            else:
                target.unlink(missing_ok=True)
        for manifest in cone:
            manifest.unlink(missing_ok=True)
            entries.pop(manifest, None)
        out.append(Cleared(damage, tuple(dict.fromkeys(removed))))
    return out


class Job:
    """A job of the workflow run by a script (the ``snakemake`` object of its
    ``script:`` directive, or anything with ``log``, ``input``, ``output`` and
    ``config``)."""

    def __init__(self, smk: Any) -> None:
        self.smk = smk
        sys.excepthook = _one_line_for_no_space
        setup_logging(smk.log[0])
        # held while the job writes: no other run clears damage meanwhile
        self._lock = ExitStack()
        self._lock.enter_context(_lock(Path(smk.config["results_dir"]), fcntl.LOCK_SH))

    def finish(self) -> None:
        """The job's outputs are written: record them and its inputs (:func:`record`)."""
        record(list(self.smk.output), self.smk.config["results_dir"], list(self.smk.input))
        self._lock.close()


def start(smk: Any) -> Job:
    """Start a workflow job: its log file, and a full disk said in one line (:class:`Job`)."""
    return Job(smk)


def _one_line_for_no_space(kind: type[BaseException], exc: BaseException, tb: TracebackType | None) -> None:
    """The job's end on a full disk: one line on the terminal and in its log, no traceback."""
    if isinstance(exc, NoSpace):
        logging.error("%s", exc)
        print(f"rocklab: {exc}", file=sys.__stderr__, flush=True)
        return
    sys.__excepthook__(kind, exc, tb)
