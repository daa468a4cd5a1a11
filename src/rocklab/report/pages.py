"""The documentation pages: Jinja2 templates filled with every stage's summary.

Each stage publishes its summary as it writes its tables
(``results/summaries/<section>.json``, :mod:`rocklab.summaries`); the docs
rule gathers them, with the workflow's timings
(:func:`rocklab.benchmarks.performance_summary`), into one numbers file
(:func:`docs_numbers`), one section per stage, and renders the page
templates of ``docs/templates`` with it (:func:`render`):

- ``{{ section.key.subkey }}``, ``{{ maps.by_record.A["2s-0.95"].N_O | fmt(".3f") }}``:
  a value and, with the filter ``fmt``, its format (Python's format
  mini-language). Every value goes through :func:`rocklab.report.format.show`:
  ``None`` reads "not measured", a list its items joined by commas, a
  boolean "yes" or "no". A ``None`` section met on the way (a stage that did
  not run) is the value.
- ``{{ table("name") }}``: a markdown table of :data:`rocklab.report.tables.TABLES`.

Rendered strictly (the check of the committed pages), a value that the
numbers file does not hold is an error (``StrictUndefined``), so a page
cannot quote a number that was not generated; otherwise it reads "not
measured" (the pages of a campaign unlike the embedded one).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from jinja2 import ChainableUndefined, Environment, StrictUndefined

from rocklab import summaries
from rocklab.benchmarks import performance_summary
from rocklab.diagnosis.diagnosis_summary import TOLERANCES as FIT_TOLERANCES
from rocklab.disk import write_text
from rocklab.dissipation.dissipation_summary import CAMPAIGN_LEVEL_TOLERANCES
from rocklab.dissipation.dissipation_summary import TOLERANCES as DISSIPATION_TOLERANCES
from rocklab.lab.accuracy import TOLERANCES as ACCURACY_TOLERANCES
from rocklab.lab.qc_summary import TOLERANCES as QC_TOLERANCES
from rocklab.report.format import NOT_MEASURED, show
from rocklab.report.tables import TABLES
from rocklab.seismic.maps_summary import TOLERANCES as MAP_TOLERANCES
from rocklab.shake_table.shake_table_summary import TOLERANCES as SHAKE_TABLE_TOLERANCES

#: The sections of the numbers file that stages publish (``summaries/<section>.json``),
#: each with the tolerances its stage declares (:func:`rocklab.summaries.differences`).
SECTIONS = {
    "quality_control": QC_TOLERANCES,
    "dissipation": DISSIPATION_TOLERANCES,
    "campaign_level": CAMPAIGN_LEVEL_TOLERANCES,
    "diagnosis": FIT_TOLERANCES,
    "limestone": FIT_TOLERANCES,
    "maps": MAP_TOLERANCES,
    "calibrated": MAP_TOLERANCES,
    "shake_table": SHAKE_TABLE_TOLERANCES,
    "instruments": ACCURACY_TOLERANCES,
}

#: Sections left out of the comparison of two numbers files: those whose values
#: change from run to run (timings) and those of targets outside ``all``
#: (``shake_table``: its data live outside the repository), which the results
#: of ``make run`` do not hold.
VOLATILE = ("performance", "shake_table")


def summary_paths(results_dir: str | Path) -> dict[str, Path]:
    """Where each stage of a results folder writes its summary: {section: path}."""
    return {name: Path(results_dir) / "summaries" / f"{name}.json" for name in SECTIONS}


def docs_numbers(results_dir: str | Path, checkout: str | Path | None = None) -> dict[str, Any]:
    """The numbers file of a results folder: every stage's summary and the timings.

    A stage that did not run (no summary file) is ``None``: its pages say "not measured".
    ``checkout``: the repository the cluster projection reads
    (:func:`rocklab.benchmarks.performance_summary`).
    """
    numbers = {name: summaries.read_summary(path) for name, path in summary_paths(results_dir).items()}
    numbers["performance"] = summaries.rounded(performance_summary(results_dir, checkout))
    return {"volatile": list(VOLATILE), **numbers}


def stable(numbers: Mapping[str, Any]) -> dict[str, Any]:
    """``numbers`` without its volatile sections: what two runs must agree on."""
    return {k: v for k, v in numbers.items() if k not in VOLATILE and k != "volatile"}


def differences(new: Mapping[str, Any], old: Mapping[str, Any]) -> list[str]:
    """Where two numbers files disagree beyond the tolerance of each quantity,
    the volatile sections left out (dotted paths, section first)."""
    new, old = stable(new), stable(old)
    return [
        f"{name}.{d}" if d[0] != ":" else f"{name}{d}"
        for name in sorted(set(new) | set(old))
        for d in summaries.differences(new.get(name), old.get(name), SECTIONS.get(name, {}))
    ]


def write_numbers(numbers: Mapping[str, Any], path: str | Path) -> None:
    """Write the numbers file (:func:`docs_numbers`) to ``path`` (:func:`rocklab.summaries.dumps`)."""
    write_text(path, summaries.dumps(numbers))


def read_numbers(path: str | Path) -> dict[str, Any]:
    """The numbers file at ``path``, as written by :func:`write_numbers`."""
    return json.loads(Path(path).read_text())


class _NotMeasured(ChainableUndefined):
    """A value the numbers file does not hold, on a page not rendered strictly."""

    def __str__(self) -> str:
        return NOT_MEASURED


class _Environment(Environment):
    """Jinja's environment, in which a ``None`` section's keys are ``None``:
    a stage that did not run is "not measured" all the way down."""

    def getitem(self, obj: Any, argument: Any) -> Any:
        return None if obj is None else super().getitem(obj, argument)

    def getattr(self, obj: Any, attribute: str) -> Any:
        return None if obj is None else super().getattr(obj, attribute)


def environment(strict: bool = True) -> Environment:
    """The Jinja2 environment of the pages: every value printed by :func:`show`,
    ``fmt(spec)`` its format, undefined values an error when ``strict``."""
    env = _Environment(
        undefined=StrictUndefined if strict else _NotMeasured,
        finalize=show,
        keep_trailing_newline=True,
        autoescape=False,
    )
    env.filters["fmt"] = show
    return env


def render(template: str, numbers: Mapping[str, Any], strict: bool = True) -> str:
    """``template`` (Jinja2) rendered with the sections of ``numbers`` and ``table(name)``."""
    return environment(strict).from_string(template).render(**numbers, table=lambda name: TABLES[name](numbers))


def render_pages(template_dir: str | Path, numbers: Mapping[str, Any], strict: bool = True) -> dict[str, str]:
    """Every template of ``template_dir`` rendered (:func:`render`): {file name: page text}."""
    return {p.name: render(p.read_text(), numbers, strict) for p in sorted(Path(template_dir).glob("*.md"))}


def write_docs(
    results_dir: str | Path,
    template_dir: str | Path,
    out_dir: str | Path,
    strict: bool = False,
    checkout: str | Path | None = None,
) -> list[Path]:
    """Write the numbers file and every page of ``template_dir`` into ``out_dir``.

    Not ``strict`` by default: any campaign gets its pages, with "not
    measured" where it lacks what a template quotes; the committed pages are
    checked strictly by ``tests/test_docs.py``.

    Returns the paths written: ``out_dir/numbers.json`` first, then the pages.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = [out / "numbers.json"]
    write_numbers(docs_numbers(results_dir, checkout), written[0])
    # The pages are filled from the file as written (its key order), so that
    # they are a function of the numbers file alone.
    numbers = read_numbers(written[0])
    for name, text in render_pages(template_dir, numbers, strict).items():
        write_text(out / name, text)
        written.append(out / name)
    return written
