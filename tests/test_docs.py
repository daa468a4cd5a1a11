"""The documentation: generated pages that are not stale, a short README
whose example runs, links that resolve, and the stages' summaries and the
pages on a tiny results folder (CI has no results/)."""

import json
import math
import re
from pathlib import Path

import jinja2
import pandas as pd
import pytest
import yaml

from rocklab import summaries
from rocklab.benchmarks import QUOTED, measured_code
from rocklab.diagnosis.diagnosis_summary import diagnosis_summary, limestone_summary
from rocklab.dissipation.dissipation_summary import dissipation_summary
from rocklab.lab.qc_summary import quality_control_summary
from rocklab.lab.validity import FAULT_COLUMNS
from rocklab.report import pages, tables
from rocklab.seismic.indices import FLIPPED_FRACTION
from rocklab.seismic.maps_summary import maps_summary
from rocklab.seismic.paper_comparison import record_comparison

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
TEMPLATES = DOCS / "templates"
#: Pages written by hand: they quote no result.
HAND_WRITTEN = {"index.md", "raw-format.md", "diagnosis-method.md", "cli.md", "cluster.md"}


def committed_numbers():
    return pages.read_numbers(DOCS / "numbers.json")


# --- (a) the committed pages are what their templates and numbers write ---------------------


@pytest.mark.parametrize("template", sorted(p.name for p in TEMPLATES.glob("*.md")))
def test_committed_page_is_its_template_filled_with_the_committed_numbers(template):
    rendered = pages.render((TEMPLATES / template).read_text(), committed_numbers())
    page = DOCS / template
    assert page.is_file(), f"docs/{template} missing: run `make docs`"
    assert page.read_text() == rendered, (
        f"docs/{template} differs from docs/templates/{template} filled with docs/numbers.json: "
        "edit the template, not the page, and run `make docs`"
    )


def test_every_page_is_generated_or_written_by_hand():
    generated = {p.name for p in TEMPLATES.glob("*.md")}
    on_disk = {p.name for p in DOCS.glob("*.md")}
    assert on_disk - generated - HAND_WRITTEN == set(), "a page without a template: remove it or add its template"
    assert not generated & HAND_WRITTEN


def test_the_index_lists_every_page():
    index = (DOCS / "index.md").read_text()
    linked = set(re.findall(r"\]\(([\w.-]+\.md)\)", index))
    expected = {p.name for p in TEMPLATES.glob("*.md")} | (HAND_WRITTEN - {"index.md"})
    assert expected <= linked


def test_committed_numbers_file_is_as_the_docs_rule_writes_it():
    text = (DOCS / "numbers.json").read_text()
    assert summaries.dumps(json.loads(text)) == text
    assert committed_numbers()["volatile"] == list(pages.VOLATILE)
    assert set(committed_numbers()) == {"volatile", "performance", *pages.SECTIONS}


# --- (b) the committed numbers are what the current results give ---------------------------


def results_dir() -> Path:
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    return ROOT / config["results_dir"]


def test_committed_numbers_are_those_of_the_current_results():
    """Each number within the tolerance its stage declares for it (a map index:
    the cells that flip between machines, rocklab.seismic.maps_summary), so that
    `make run` then `make test` passes on any machine."""
    results = results_dir()
    if not results.is_dir():
        pytest.skip(f"no {results.name}/ from `make run` here (CI has none): nothing to compare the pages with")
    missing = [p.name for p in pages.summary_paths(results).values() if not p.is_file()]
    if set(missing) - {"shake_table.json"}:
        pytest.skip(f"{results.name}/ is incomplete (no summaries/{', '.join(missing)}): run `make run`")
    diff = pages.differences(pages.docs_numbers(results), committed_numbers())
    assert not diff, "docs/ is stale, run `make docs`:\n" + "\n".join(diff[:30])


def test_a_float_without_a_declared_tolerance_is_an_error_not_an_exact_comparison():
    assert summaries.differences({"x": 0.5}, {"x": 0.5}) == [
        "x: a float with no declared tolerance (0.5 committed, 0.5 from the results)"
    ]
    assert summaries.differences({"n": 3}, {"n": 3}) == []  # a count needs none
    assert summaries.undeclared({"a": {"x": 0.5, "n": 3, "t": "b"}, "l": [0.1]}, {"a.*": summaries.EXACT}) == ["l.0"]
    # one unit of the sixth significant digit: a last bit that rounds the other way
    assert summaries.LAST_DIGIT.admits(1.23457, 1.23456) and not summaries.LAST_DIGIT.admits(1.23459, 1.23456)
    for new, old in ((1.00001, 1.0), (0.100001, 0.1), (0.999999, 1.0), (9.99999, 9.99998)):
        assert summaries.LAST_DIGIT.admits(new, old) and summaries.LAST_DIGIT.admits(old, new), (new, old)
    assert not summaries.LAST_DIGIT.admits(1.00002, 1.0)


def test_a_number_may_differ_by_the_tolerance_its_stage_declares_and_no_more():
    committed = {"volatile": [], "maps": {"by_record": {"A": {"2s-0.95": {"N_O": 0.5, "n_overturned": 10}}}}}
    moved = json.loads(json.dumps(committed))
    moved["maps"]["by_record"]["A"]["2s-0.95"]["N_O"] = 0.5 + FLIPPED_FRACTION / 2
    assert pages.differences(moved, committed) == []
    moved["maps"]["by_record"]["A"]["2s-0.95"]["N_O"] = 0.5 + 2 * FLIPPED_FRACTION
    assert pages.differences(moved, committed) == [
        f"maps.by_record.A.2s-0.95.N_O: 0.5 committed, {0.5 + 2 * FLIPPED_FRACTION!r} from the results"
    ]
    # a count is no index: exact
    moved["maps"]["by_record"]["A"]["2s-0.95"] |= {"N_O": 0.5, "n_overturned": 11}
    assert pages.differences(moved, committed) == [
        "maps.by_record.A.2s-0.95.n_overturned: 10 committed, 11 from the results"
    ]
    # nor is a number of another stage, nor a volatile one
    assert pages.differences({"dissipation": {"N_O": 0.5001}}, {"dissipation": {"N_O": 0.5}})
    # a fitted parameter may move by the fit's stopping rule, a count of the diagnosis may not
    assert not pages.differences({"diagnosis": {"s_e": -0.000117894}}, {"diagnosis": {"s_e": -0.000118036}})
    assert pages.differences({"diagnosis": {"s_alpha": 0.0305}}, {"diagnosis": {"s_alpha": 0.0304}})
    assert pages.differences({"diagnosis": {"n_tests": 1001}}, {"diagnosis": {"n_tests": 1000}})
    assert not pages.differences({"volatile": ["performance"], "performance": {"s": 2}}, {"performance": {"s": 1}})


# --- README ---------------------------------------------------------------------------------


def test_readme_is_short_and_quotes_no_result():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 200
    assert not re.search(r"\b0\.\d{3}\b", text), "a result in the README: it belongs to a generated page"


def test_readme_states_the_measured_times():
    """The README's times and memory are those of the performance page (issue 14)."""
    perf = json.loads((ROOT / "docs" / "numbers.json").read_text())["performance"]
    text = " ".join((ROOT / "README.md").read_text().split())
    fc, sc = perf["fresh_clone"], perf["scale"]
    assert f"{fc['total_s']:.0f} s in all, {fc['install_s']:.0f} s of install and {fc['workflow_s']:.0f} s" in text
    assert f"({sc['large_n_tests']} tests" in text and f"{sc['large_cpu_s']:.0f} s of CPU time" in text
    assert f"({sc['large_s']:.0f} s at a load average of {sc['large_load']:.1f})" in text
    assert f"peak memory of {sc['large_peak_mb'] / 1000:.1f} GB" in text


def test_the_quoted_performance_is_a_measurement_of_this_code():
    """The README and the performance page quote bench/fresh_clone.py and bench/scale.py (issue 44): each
    must be a measurement of the code this checkout holds (rocklab.benchmarks.measured_code: the library,
    workflow, settings, build and pinned packages, and the benchmark's script).  A change of any of them
    fails here until the benchmark runs again on it (then `make docs`, and the README's lines)."""
    perf = committed_numbers()["performance"]
    stale = {}
    for name, script in QUOTED.items():
        was, now = (perf.get(name) or {}).get("measured"), measured_code(ROOT, script)
        if not was:
            stale[name] = "no record of the code it measured"
        elif was["dirty"]:
            stale[name] = f"measured on uncommitted code beside {was['commit'][:8]}"
        elif was["code"] != now["code"]:
            stale[name] = f"measured at {was['commit'][:8]}, whose code differs from this checkout's"
    assert not stale, "; ".join(f"{name}: {why} (run python {QUOTED[name]} again)" for name, why in stale.items())


def readme_example():
    """The Python block of the README's library section."""
    return re.search(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S).group(1)


def check_readme_example_output(out):
    """What the README example prints: verdict, e_exp/e_an and p T_1/4 of V0001, then the wall's response."""
    test, quake = out.splitlines()
    valid, e_ratio, t_quarter = map(float, test.split())
    assert valid == 1  # V0001 is valid: its lost channel has a backup
    assert 0.5 < e_ratio < 1.5 and 1 < t_quarter < 20
    overturned, n_impacts = quake.split()
    assert overturned in ("True", "False") and int(n_impacts) > 0


def test_readme_library_example_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)  # it writes its campaign in the current folder, as a user's would
    exec(compile(readme_example(), "README.md", "exec"), {})
    check_readme_example_output(capsys.readouterr().out)
    assert (tmp_path / "virtual-campaign" / "tests.csv").is_file()


@pytest.mark.parametrize("page", ["README.md", "CHANGELOG.md", *(f"docs/{p.name}" for p in sorted(DOCS.glob("*.md")))])
def test_relative_links_resolve(page):
    path = ROOT / page
    for target in re.findall(r"\]\((?!https?:)([^)#\s]+)(?:#[^)]*)?\)", path.read_text()):
        assert (path.parent / target).exists(), f"{page} links to {target}, which does not exist"


# --- the extractor and the renderer on a tiny results folder --------------------------------


def _write(path: Path, rows):
    path.parent.mkdir(parents=True, exist_ok=True)
    pd.DataFrame(rows).to_csv(path, index=False)


def _diagnosis_entries():
    def stop(error, gain):
        return {
            "effect": "stop_threshold",
            "params": {"v_stop_over_vr": 0.1},
            "ci95": {"v_stop_over_vr": [0.09, 0.11]},
            "n_tests": 10,
            "evidence": {},
            "error_heldout": {"n_impacts_rms": error, "duration_pct_rms": error},
            "gain": {"n_impacts_rms": gain, "duration_pct_rms": gain},
        }

    def series(key, n_tests, findings):
        return {
            "scope": "series",
            "key": key,
            "boundary": "two-sided",
            "n_tests": n_tests,
            "n_impacts": 20 * n_tests,
            "base": {"model": "Housner", "errors": {}},
            "what_is_wrong": "it rocks too long.",
            "verdict": [f["effect"] for f in findings],
            "unexplained": False,
            "residual_structure": [],
            "findings": findings,
            "weak_evidence": {},
            "rejected": {},
            "sample_test": f"T-{key}",
        }

    heldout = {"free_run_log_peak_rms": 2.0, "impact_rms": 0.05, "time_rms": 0.06}
    boundary = {
        "scope": "boundary",
        "key": "two-sided",
        "boundary": "two-sided",
        "n_tests": 45,
        "n_series": 3,
        "n_series_diagnosed": 3,
        "too_small_series": [],
        "n_impacts": 900,
        "base": {"model": "Housner", "errors": {"lag_s": 16.0}},
        "what_is_wrong": "it rocks too long.",
        "verdict": ["stop_threshold"],
        "unexplained": False,
        "residual_structure": [],
        "unexplained_series": [],
        "findings": [
            {
                **stop(None, None),
                "evidence": {
                    "series": "named in 2 of 3 series",
                    "pooled": "over 3 series",
                    "range": {"v_stop_over_vr": [0.09, 0.12]},
                },
                "n_series": 2,
            }
        ],
        "series_verdicts": {},
        "heldout": {"base": heldout, "model": heldout},
        "extended": {"statement": "the extended model rocks as long as the wall.", "n_series": 3},
    }
    asym = {
        "effect": "hinge_asymmetry",
        "params": {"s_alpha": 0.03},
        "ci95": {},
        "n_tests": 30,
        "evidence": {},
        "error_heldout": {},
        "gain": {},
    }
    return [
        series("1a-2s", 10, [stop(2.0, 8.0)]),
        series("2b-2s", 30, [stop(4.0, 16.0), asym]),
        series("5c-2s", 5, []),
        boundary,
    ]


@pytest.fixture
def tiny_results(tmp_path):
    """A results folder of a few rows: two-sided series 1a-2s and 3a-2s (apart), one-sided 1b-1s-cd60."""
    r = tmp_path / "results"
    none = {c: "" for c in FAULT_COLUMNS} | {"in_plane_lost": False}
    qc = [
        ("T1", "1a-2s", True, None, 0.2, 0.005, none),
        ("T2", "1a-2s", True, None, 1.1, 0.019, none | {"channels_spikes_repaired": "ch1"}),
        ("T3", "3a-2s", True, None, 0.4, 0.010, none | {"channels_dead": "ch4", "in_plane_lost": True}),
        ("T4", "1b-1s-cd60", False, "instrument_malfunction", None, None, none | {"channels_dead": "ch0 ch1"}),
        ("T5", "1b-1s-cd60", False, "disturbed_initial_conditions", 0.3, 0.2, none | {"channels_stuck": "ch2"}),
        (
            "T6",
            "1b-1s-cd60",
            False,
            "residual_out_of_plumb",
            1.9,
            0.01,
            none | {"channels_dropout": "ch0", "channels_backup_used": "ch2"},
        ),
    ]
    columns = ("test_id", "series", "valid", "reject_reason", "residual_top_mm", "release_velocity_ratio")
    _write(r / "qc.csv", [dict(zip(columns, row[:-1], strict=True)) | row[-1] for row in qc])
    series = [
        ("1a-2s", "two-sided", 2, 0, 0.95, 0.5, False, 0),
        ("3a-2s", "two-sided", 1, 0, 0.86, -9.0, True, 0),
        ("1b-1s-cd60", "one-sided", 0, 3, None, -2.5, False, 1),
    ]
    _write(
        r / "series.csv",
        [
            {
                "series": name,
                "boundary": boundary,
                "n_valid": valid,
                "n_rejected": rejected,
                "e_ratio_mean": e,
                "modified_z": z,
                "stands_apart": apart,
                "rejected_instrument_malfunction": each,
                "rejected_residual_out_of_plumb": each,
                "rejected_disturbed_initial_conditions": each,
            }
            for name, boundary, valid, rejected, e, z, apart, each in series
        ],
    )
    test = {"theta0_over_alpha_fall": 0.999, "thetadot_release": 3e-4, "centre_amplification": None}
    _write(
        r / "tests.csv",
        [
            {
                "test_id": "T1",
                "series": "1a-2s",
                "boundary": "two-sided",
                "e_exp_eq10": 0.9301,
                "e_exp_eq11": 0.9300,
                "e_ratio": 0.94,
                **test,
            },
            {
                "test_id": "T2",
                "series": "1a-2s",
                "boundary": "two-sided",
                "e_exp_eq10": 0.9400,
                "e_exp_eq11": 0.9403,
                "e_ratio": 0.96,
                **test,
            },
            {
                "test_id": "T3",
                "series": "3a-2s",
                "boundary": "two-sided",
                "e_exp_eq10": 0.8500,
                "e_exp_eq11": 0.8500,
                "e_ratio": 0.86,
                **test,
            },
        ],
    )
    stats = {"n_tests": 3, "n_series": 2, "n_walls": 2, "sd": 0.1, "series_sd": 0.1, "df": 1.5, "ci_note": ""}
    _write(
        r / "summary.csv",
        [{"boundary": "two-sided", "quantity": "e_ratio", "mean": 0.92, "ci_low": 0.86, "ci_high": 0.96, **stats}],
    )
    _write(
        r / "table3.csv",
        [
            {
                "boundary": "two-sided",
                "window": "complete",
                "column": "e_ratio_complete",
                "mean": 0.92,
                "ci_low": 0.86,
                "ci_high": 0.96,
                "paper": None,
                **stats,
            }
        ],
    )
    law = {"a_se": 0.01, "b_se": 0.01}
    _write(
        r / "amplitude_laws.csv",
        [
            {
                "series": None,
                "law": "peak",
                "a": 0.96,
                "b": 0.035,
                "r2": 0.16,
                "n": 90,
                "grouping": "boundary",
                "boundary": "two-sided",
                **law,
            },
            {
                "series": "1a-2s",
                "law": "peak",
                "a": 0.95,
                "b": 0.03,
                "r2": 0.8,
                "n": 60,
                "grouping": "series",
                "boundary": None,
                **law,
            },
            {
                "series": "3a-2s",
                "law": "peak",
                "a": 0.86,
                "b": 0.03,
                "r2": 0.9,
                "n": 30,
                "grouping": "series",
                "boundary": None,
                **law,
            },
        ],
    )
    _write(
        r / "effects.csv",
        [
            {
                "boundary": "two-sided",
                "factor": "unit",
                "value": "e_ratio",
                "levels": "['clay brick', 'tuff']",
                "level_means": "[0.95, 0.86]",
                "n_units": "[3, 2]",
                "unit_level": "wall",
                "test": "Kruskal-Wallis on wall means",
                "p": 0.4,
            },
            {
                "boundary": "one-sided",
                "factor": "contact_depth_mm",
                "value": "e_ratio",
                "levels": "[60.0, 120.0]",
                "level_means": "[1.2, 1.3]",
                "n_units": "[4, 4]",
                "unit_level": "series",
                "test": "Kruskal-Wallis on series means",
                "p": 0.3,
            },
            {
                "factor": "push/pull",
                "value": "e_ratio",
                "series": "2b-2s",
                "n_push": 10,
                "n_pull": 9,
                "relative_change": -0.0008,
                "welch_p": 0.06,
            },
        ],
    )
    (r / "diagnosis.json").write_text(json.dumps(_diagnosis_entries()))

    def base(e_an, ratio):
        return {
            "model": "Housner",
            "e_an": e_an,
            "measured_median_ratio": ratio,
            "measured_geometric_mean_ratio": ratio,
        }

    group = {
        "scope": "block group",
        "key": "all",
        "h_over_b": None,
        "n_tests": 2,
        "n_impacts": 20,
        "base": base(0.9, 1.0),
        "what_is_wrong": "",
        "verdict": [],
        "unexplained": False,
        "residual_structure": [],
        "findings": [],
        "weak_evidence": {},
        "rejected": {},
        "signatures": {},
        "heldout": {"base": {"ratio_rms": 0.05}, "model": {"ratio_rms": 0.05}},
        "families": [],
    }
    (r / "limestone_diagnosis.json").write_text(
        json.dumps(
            {
                "source": "blocks",
                "all": {
                    **group,
                    "scope": "all blocks",
                    "base": base(0.985, 0.97),
                    "what_is_wrong": "e too high",
                    "unexplained": True,
                    "residual_structure": [{"where": "impact", "sentence": "impact: bias +0.011"}],
                    "rejected": {},
                    "signatures": {},
                },
                "groups": [
                    {**group, "key": "4", "h_over_b": 3.9999999, "base": base(0.91, 0.93)},
                    {**group, "key": "15", "h_over_b": 15.0, "base": base(0.99, 0.97)},
                ],
                "slenderness": {
                    "intercept": 0.98,
                    "slope": 0.6,
                    "slope_se": 0.1,
                    "p": 0.01,
                    "n_groups": 2,
                    "n_trials": 4,
                    "levels": {"4": 1.02, "15": 0.97},
                },
            }
        )
    )
    cells = 100

    def cell(record, model, n_o, changes, reversals):
        return {
            "record": record,
            "model": model,
            "N_O": n_o / cells,
            "scatter": changes / n_o if n_o else None,
            "n_overturned": n_o,
            "n_cells": cells,
            "changes_duration": changes,
            "changes_amplitude": changes,
            "reversals_duration": reversals,
            "reversals_amplitude": reversals,
        }

    summary = [
        cell("A", "2s-housner", 50, 10, 4),
        cell("A", "2s-0.95", 40, 6, 2),
        cell("B", "2s-housner", 90, 5, 5),
        cell("B", "2s-0.95", 80, 8, 2),
        cell("C", "2s-housner", 5, 1, 1),
        cell("C", "2s-0.95", 0, 0, 0),
    ]
    _write(r / "maps" / "summary.csv", summary)
    # A and B are rows 1 and 2 of a small Table 4 (B with a PGA unlike the table's), D (row 3) is
    # not shipped, C is no Table 4 record
    table4 = pd.DataFrame({"row": [1, 2, 3], "record": ["A", "B", "D"]})
    agreement = pd.DataFrame(
        {"table4_row": [1, 2], "pga_pgv_match": [True, False], "differences": ["", "PGA +13.3 %"]},
        index=pd.Index(["A", "B"], name="record"),
    )
    record_comparison(pd.DataFrame(summary), agreement, table4).to_csv(r / "maps" / "comparison.csv", index=False)
    _write(
        r / "maps" / "reductions.csv",
        [
            {
                "records": "all",
                "baseline": "2s-housner",
                "model": "2s-0.95",
                "index": "N_O",
                "statistic": s,
                "reduction_pct": v,
                "n_records": 3,
                "paper_pct": p,
            }
            for s, v, p in (("mean", 39.3, 25), ("min", 11.1, 3), ("max", 100, None))
        ],
    )
    (r / "benchmarks" / "reduce").mkdir(parents=True)
    bench = "s\th:m:s\tmax_rss\n{}\t0:00:01\t10\n"
    (r / "benchmarks" / "qc_table.tsv").write_text(bench.format(9.5))
    (r / "benchmarks" / "reduce" / "1a-2s.tsv").write_text(bench.format(3.0))
    (r / "benchmarks" / "reduce" / "3a-2s.tsv").write_text(bench.format(5.0))
    (r / "bench").mkdir()
    (r / "bench" / "simulator.json").write_text(
        json.dumps(
            {
                "histories": 1000,
                "t_batch_s": 0.02,
                "t_reference_s": 270.0,
                "speedup": 13500.0,
                "overturned_batch": 496,
                "overturned_reference": 495,
                "mismatches": 5,
                "mismatches_beyond_tolerance": [],
                "pass": True,
            }
        )
    )
    return r


def numbers_of(results: Path) -> dict:
    """The numbers file of ``results``, each stage's summary written as its job writes it."""
    out = results / "summaries"
    summaries.write_summary(quality_control_summary(pd.read_csv(results / "qc.csv")), out / "quality_control.json")
    tables = {k: results / f"{k}.csv" for k in ("tests", "series", "effects", "table3", "summary")}
    summaries.write_summary(
        dissipation_summary(tables | {"laws": results / "amplitude_laws.csv"}), out / "dissipation.json"
    )
    summaries.write_summary(diagnosis_summary(results / "diagnosis.json"), out / "diagnosis.json")
    summaries.write_summary(limestone_summary(results / "limestone_diagnosis.json"), out / "limestone.json")
    maps = [results / "maps" / f"{name}.csv" for name in ("summary", "reductions", "comparison")]
    summaries.write_summary(maps_summary(*maps), out / "maps.json")
    return pages.docs_numbers(results)


def test_every_float_of_another_campaign_s_summaries_has_a_declared_tolerance(tiny_results):
    """Keys the embedded campaign's summaries lack (another campaign's series, boundaries, models)."""
    numbers = numbers_of(tiny_results)
    for section, tolerances in pages.SECTIONS.items():
        if numbers.get(section) is not None:
            assert not summaries.undeclared(numbers[section], tolerances), section


def test_quality_control_numbers(tiny_results):
    qc = numbers_of(tiny_results)["quality_control"]
    assert qc["n_tests"] == 6 and qc["n_series"] == 3
    assert qc["verdicts"] == {
        "valid": 3,
        "instrument_malfunction": 1,
        "residual_out_of_plumb": 1,
        "disturbed_initial_conditions": 1,
        "unreadable": 0,
    }
    assert qc["release_velocity_pct"]["valid"] == {"min": 0.5, "max": 1.9}
    assert qc["release_velocity_pct"]["disturbed"] == {"min": 20.0, "max": 20.0}
    assert qc["residual_top_mm"] == {"valid_max": 1.1, "out_of_plumb_min": 1.9}
    faults = qc["channel_faults"]
    assert (faults["dead"], faults["stuck"], faults["dropout"], faults["spikes_repaired"]) == (2, 1, 1, 1)
    assert (faults["backup_used"], faults["in_plane_lost"], faults["clipped"]) == (1, 1, 0)
    assert qc["series"][1] == {
        "series": "1b-1s-cd60",
        "n_valid": 0,
        "n_rejected": 3,
        "instrument_malfunction": 1,
        "residual_out_of_plumb": 1,
        "disturbed_initial_conditions": 1,
    }


def test_dissipation_numbers(tiny_results):
    d = numbers_of(tiny_results)["dissipation"]
    assert d["eq10_eq11_max_abs_diff"] == pytest.approx(3e-4)
    two = d["two_sided"]
    assert two["e_ratio"] == {
        "mean": 0.92,
        "ci_low": 0.86,
        "ci_high": 0.96,
        "n_tests": 3,
        "n_series": 2,
        "n_walls": 2,
        "df": 1.5,
        "ci_note": "",
    }
    assert d["min_walls_interval"] == 3
    assert two["table3"]["e_ratio_complete"]["paper"] is None
    assert two["stands_apart"] == [{"series": "3a-2s", "e_ratio_mean": 0.86, "modified_z": -9.0}]
    assert two["e_ratio_mean_without_apart"] == pytest.approx(0.95)  # T1, T2 only
    assert d["one_sided"]["max_abs_modified_z"] == 2.5
    assert d["amplitude_laws"]["two_sided"]["peak"]["series_median_r2"] == pytest.approx(0.85)
    assert d["effects"]["kruskal"]["one_sided"]["contact_depth_mm__e_ratio"]["levels"] == [
        ["60", 1.2, 4],
        ["120", 1.3, 4],
    ]
    assert d["effects"]["push_pull"]["2b-2s"]["e_ratio"]["relative_change_pct"] == pytest.approx(-0.08)


def test_table_3_of_the_page_is_the_table_3_of_the_results(tiny_results):
    """Issue 40, item 3: one rendering of Table 3, the page's from the numbers and results/table3.md
    from table3.csv (rocklab.dissipation.statistics.table3_markdown), the same labels and cells."""
    from rocklab.dissipation.statistics import table3_markdown

    page = tables.table3(numbers_of(tiny_results))
    assert page == table3_markdown(pd.read_csv(tiny_results / "table3.csv"))
    assert "| complete " in page and "(3 tests, 2 series, 2 walls)" in page


def test_diagnosis_numbers_pool_the_stop_gain_over_tests(tiny_results):
    d = numbers_of(tiny_results)["diagnosis"]
    two = d["two_sided"]
    # base = error + gain per series: 10 (10 tests) and 20 (30 tests); model 2 and 4
    assert two["after_selection"]["stop_threshold"]["heldout"]["n_impacts_rms"]["base"] == pytest.approx(
        math.sqrt((10 * 100 + 30 * 400) / 40), rel=1e-5
    )
    assert two["after_selection"]["stop_threshold"]["heldout"]["n_impacts_rms"]["model"] == pytest.approx(
        math.sqrt((10 * 4 + 30 * 16) / 40), rel=1e-5
    )
    assert two["after_selection"]["stop_threshold"]["not_named"] == ["5c-2s"]
    assert two["minority"] == [{"series": "2b-2s", "effect": "hinge_asymmetry", "params": {"s_alpha": 0.03}}]
    assert d["series"][2]["verdict"] == "none" and d["n_unexplained"] == 0
    lime = numbers_of(tiny_results)["limestone"]
    assert [g["h_over_b"] for g in lime["groups"]] == [4, 15]
    assert lime["residual_structure"] == "impact: bias +0.011"


def test_map_numbers_and_the_other_normalisations_of_the_scatter(tiny_results):
    m = numbers_of(tiny_results)["maps"]
    assert m["records"] == ["A", "B", "C"] and m["n_cells"] == 100
    assert m["by_record"]["C"]["2s-0.95"] == {"N_O": 0.0, "scatter": None}
    assert m["weakest_2s_record"] == {"record": "C", "N_O": 0.05}
    assert m["reductions"]["2s-housner__2s-0.95"]["N_O"] == {
        "n_records": 3,
        "mean": 39.3,
        "min": 11.1,
        "max": 100,
        "paper_mean": 25,
        "paper_min": 3,
    }
    assert m["comparison"]["missing_rows"] == ["3 (D)"]
    two = m["comparison"]["by_comparison"]["2s-housner__2s-0.95"]
    assert [(r["row"], r["record"]) for r in two["records"]] == [(1, "A"), (2, "B"), (None, "C")]
    # A 20 %, B 11 % within the paper's 3-89 %; C loses every overturning: 100 %, outside
    assert (two["n_in_paper_range"], two["n_with_paper_range"], two["out_of_paper_range"]) == (2, 3, ["C"])
    assert two["records"][1]["table4_differences"] == "PGA +13.3 %" and not two["records"][1]["table4_match"]
    assert "every overturning of 2s-housner removed" in two["records"][2]["reason"]
    assert "| 2 | B | PGA +13.3 % | 0.900 → 0.800 | 11.1 | yes |" in tables.maps_comparison(numbers_of(tiny_results))
    s = m["scatter_2s"]
    assert s["n_records"] == 2  # C: no overturning left
    # reversals per overturning: A 4/50 -> 2/40, B 5/90 -> 2/80
    expected = [100 * (1 - (2 / 40) / (4 / 50)), 100 * (1 - (2 / 80) / (5 / 90))]
    assert s["reversals_only"]["mean"] == pytest.approx(sum(expected) / 2, rel=1e-5)
    # changes over min(overturned, standing): A 10/50 -> 6/40, B 5/10 -> 8/20
    expected = [100 * (1 - (6 / 40) / (10 / 50)), 100 * (1 - (8 / 20) / (5 / 10))]
    assert s["by_min_of_overturned_and_standing"]["min"] == pytest.approx(min(expected), rel=1e-5)


def test_performance_is_volatile_and_absent_benchmarks_are_not_measured(tiny_results):
    n = numbers_of(tiny_results)
    perf = n["performance"]
    assert perf["jobs"]["reduce_jobs"] == {"jobs": 2, "total_s": 8.0, "longest_s": 5.0}
    assert perf["jobs"]["qc_table"]["jobs"] == 1 and perf["n_jobs"] == 3
    assert perf["simulator"]["mismatches_beyond_tolerance"] == 0
    assert perf["kinematics"] is None and perf["maps"] is None
    assert "performance" not in pages.stable(n) and "volatile" not in pages.stable(n)
    template = '{{ performance.kinematics.ratio | fmt(".0f") }} / {{ performance.simulator.speedup | fmt(",.0f") }}'
    assert pages.render(template, n) == "not measured / 13,500"
    assert n["performance"]["shake_table"] is None and n["shake_table"] is None and n["calibrated"] is None


def test_numbers_are_rounded_and_nan_is_none():
    assert summaries.number(0.123456789) == 0.123457
    assert summaries.number(float("nan")) is None
    assert summaries.number(True) is True and summaries.number(7) == 7


def test_render_finds_dotted_keys_formats_and_tables():
    numbers = {"maps": {"by": {"2s-0.95": {"N_O": 0.33229}}, "records": ["A", "B"], "ok": False}, "shake_table": None}
    text = 'N_O {{ maps.by["2s-0.95"].N_O | fmt(".3f") }} on {{ maps.records }}; ok {{ maps.ok }}; $5 stays\n'
    assert pages.render(text, numbers) == "N_O 0.332 on A, B; ok no; $5 stays\n"
    # a stage that did not run is "not measured" all the way down
    assert pages.render('{{ shake_table.SP1.scores | fmt(".3f") }}', numbers) == "not measured"
    # strictly, a page cannot quote what was not generated; otherwise it reads "not measured"
    with pytest.raises(jinja2.UndefinedError, match="missing"):
        pages.render("{{ maps.missing }}", numbers)
    with pytest.raises(jinja2.UndefinedError, match="missing"):
        pages.render('{{ maps.missing | fmt(".3f") }}', numbers)
    assert pages.render("{{ maps.missing.deeper }}", numbers, strict=False) == "not measured"
    with pytest.raises(KeyError):
        pages.render('{{ table("no_such_table") }}', numbers)


def test_write_docs_writes_the_numbers_and_every_page(tiny_results, tmp_path):
    templates = tmp_path / "templates"
    templates.mkdir()
    (templates / "qc.md").write_text('{{ quality_control.verdicts.valid }} valid\n\n{{ table("qc_series") }}\n')
    numbers = numbers_of(tiny_results)  # each stage's summary written
    written = pages.write_docs(tiny_results, templates, tmp_path / "out")
    assert [p.name for p in written] == ["numbers.json", "qc.md"]
    page = (tmp_path / "out" / "qc.md").read_text()
    assert page.startswith("3 valid\n\n| series | valid |")
    assert "| 1b-1s-cd60 | 0 | 3 | 1 | 1 | 1 |" in page
    assert pages.read_numbers(written[0]) == json.loads(summaries.dumps(numbers))


def test_every_template_renders_on_a_campaign_that_lacks_most_of_it(tiny_results):
    """The docs rule writes pages for any campaign: what it lacks reads "not measured"."""
    rendered = pages.render_pages(TEMPLATES, numbers_of(tiny_results), strict=False)
    assert set(rendered) == {p.name for p in TEMPLATES.glob("*.md")}
    assert "not measured" in rendered["dissipation.md"]
    assert "{{" not in "".join(rendered.values())


def test_a_boundary_too_small_to_extend_the_model_is_extracted(tiny_results):
    """A boundary whose series are all too small has no extended model and no held-out gain."""
    small = {
        "scope": "boundary",
        "key": "one-sided",
        "boundary": "one-sided",
        "n_tests": 3,
        "n_series": 1,
        "n_series_diagnosed": 0,
        "too_small_series": ["1b-1s"],
        "n_impacts": 6,
        "base": {"model": "Eq. 14", "errors": {}},
        "what_is_wrong": "it stops early.",
        "verdict": [],
        "unexplained": False,
        "residual_structure": [],
        "unexplained_series": [],
        "findings": [],
        "series_verdicts": {},
        "heldout": None,
        "too_small": "none of its 1 series has the 5 tests of two impacts or more a series needs to name one",
    }
    (tiny_results / "diagnosis.json").write_text(json.dumps([*_diagnosis_entries(), small]))
    one = diagnosis_summary(tiny_results / "diagnosis.json")["one_sided"]
    assert one["extended"] is None and one["verdict"] == "none" and one["n_tests"] == 3


def test_workflow_stages_are_read_from_the_bench_file(tiny_results):
    """bench/workflow.py's results/bench/workflow.json, stage by stage, into the
    performance page; the job times of the benchmark files through rocklab.io."""
    from rocklab.benchmarks import benchmark_times

    jobs = benchmark_times(tiny_results)
    assert sorted(jobs.job) == ["qc_table", "reduce/1a-2s", "reduce/3a-2s"]
    assert jobs.set_index("job").loc["reduce/3a-2s", "stage"] == "reduce" and jobs.cpu_s.isna().all()
    assert "Not measured" in tables.performance_stages(numbers_of(tiny_results))
    stages = {"reduce": {"jobs": 2, "job_s": 8.0, "longest_s": 5.0, "cpu_s": 6.5}}
    run = {"cores": 2, "wall_s": 120.0, "cpu_s": 200.0, "peak_rss_tree_mb": 900.0, "load_avg_1min_before": 1.0}
    run |= {"n_jobs": 2, "job_s": 8.0, "job_s_over_wall": 8 / 120, "snakemake_cpu_s": 15.0}
    run |= {"target_s": 150.0, "wall_over_target": 0.8, "pass": True, "stages": stages}
    (tiny_results / "bench" / "workflow.json").write_text(json.dumps(run))
    n = numbers_of(tiny_results)
    assert n["performance"]["workflow"]["stages"] == stages
    assert "| `reduce` | 2 | 8.0 | 5.0 | 6.5 |" in tables.performance_stages(n)
    template = '{{ performance.workflow.wall_over_target | fmt(".2f") }} {{ performance.workflow["pass"] }}'
    assert pages.render(template, n) == "0.80 yes"
