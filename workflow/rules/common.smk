# Paths, the campaign's test list and the per-test parameters that decide
# when a test must be reduced again.
import functools
import json
import re
from pathlib import Path

from rocklab.config import check_names, check_paths, recorded_path
from rocklab.lab.campaign import UNREADABLE, open_campaign
from rocklab.seismic.accelerograms import read_manifest

# config is validated by the Snakefile, every default filled in from
# workflow/schemas/config.schema.yaml: the rules read it without defaults.
check_paths(config["raw_dir"], config["results_dir"])
RAW = Path(config["raw_dir"])
RESULTS = Path(config["results_dir"])
# Every row checked at the door (docs/raw-format.md): a refused row is a row
# of qc.csv, and no id or path of the tables names a file outside the two folders.
CAMPAIGN = open_campaign(RAW)
#: The tests with a results file of their own (safe ids, first row of each).
TEST_IDS = CAMPAIGN.test_ids
# the tests and records the config names become file names too
check_names(config, TEST_IDS, set(read_manifest().record))
#: The tests of each series, in the order of tests.csv.
TESTS_BY_SERIES = {k: v for k, v in CAMPAIGN.reduction_groups().items() if k != UNREADABLE}
#: The tests of each reduction job: whole specimens (or a part of a large one), or the tests refused at the door.
REDUCTION_JOBS = CAMPAIGN.reduction_jobs(config["reduction"]["max_tests_per_job"])
#: The reduction job of each test.
REDUCTION_JOB = {t: job for job, ids in REDUCTION_JOBS.items() for t in ids}

# Scheduling: on few cores Snakemake starts the selectable jobs of highest
# priority first.  The campaign's chain (reduction, diagnosis, its
# checkpoint) leads to the longest path to the end, through the calibrated
# maps; the maps come next (the paper's, independent of the campaign, fill
# the cores the chain leaves idle), figures and pages last.  With equal
# priorities a map job started first could hold a core for most of the
# reduction and leave the diagnosis to the end.  Of the figures the
# diagnosis' (about 11 s) starts first: last, it ran alone on one core.
PRIORITY = {"campaign_chain": 20, "maps": 10, "longest_figures": 5}


onstart:
    # No job-rate limit on a local run.  With one (Snakemake's default, 100
    # jobs a second) every scheduling round that leaves a job waiting for a
    # core starts a one-second timer for another round, and each job that
    # ends starts one more such chain: 1,344 rounds for the 31 jobs of the
    # embedded campaign, each re-reading the params and input sizes of every
    # waiting job, in Snakemake's own process, which competes with the jobs
    # for the two cores.  Without it Snakemake schedules when a job ends.
    # The limiter only exists once the run starts (it is not a setting a
    # Snakefile reaches); a remote executor keeps it.
    if workflow.local_exec and getattr(getattr(workflow, "scheduler", None), "job_rate_limiter", None) is not None:
        workflow.scheduler.job_rate_limiter = None


def res(*parts):
    return str(RESULTS.joinpath(*parts))


def repo_path(*parts):
    """A file of the checkout as a stable param or input: relative, so that
    moving the checkout reruns nothing (workflow.source_path() would point
    into a per-run cache and rerun the rule every time)."""
    return recorded_path(Path(workflow.basedir, *parts))


def schema_path(name):
    """A table schema of workflow/schemas (see repo_path)."""
    return repo_path("workflow", "schemas", name)


def record_stamp(test_id):
    """The size and modification time of a test's record where the log
    points, None when there is none (or the row was refused at the door).

    A param of its reduction job, not an input: the record rereduces its
    job when it changes (Snakemake's params trigger, as its mtime would as
    an input), and a job waiting for a core has no file to stat.  Snakemake
    stats every input of every waiting job at each scheduling round, and
    checksums every input for every output at a job's end (45,000 per job
    of 150 tests): with the records as inputs (and the rounds of its
    default job-rate limit, see the onstart handler above) its own CPU grew
    with the square of the campaign, 9 s for the embedded campaign, 390 s
    for ten times it.  A missing record is not a missing input either: the test is
    reduced to an 'unreadable' entry and the rest of the campaign goes on.
    """
    if test_id in CAMPAIGN.log.errors:
        return None
    try:
        st = CAMPAIGN.record_path(test_id).stat()
    except OSError:
        return None
    return [st.st_size, st.st_mtime_ns]


def reduction_rows(job):
    """The attributes of the QC rows of a reduction job's tests (rocklab.lab.reduction.row_attrs)."""
    return res("reduction", f"{job}.json")


def reduced_inputs(test_ids):
    """What a rule over many reduced tests takes as input: the rows files of
    their reduction jobs, not the tests' netCDF files (passed as params).

    Each job writes its tests' files and its rows file together, so the rows
    file is as new as any of them and stands for them all.  Snakemake stats
    every input of every job waiting for a core at each scheduling round:
    listed file by file, the 2,500 netCDF inputs of the QC, dissipation and
    diagnosis jobs cost Snakemake's own process some 20 s of CPU of a 35 s
    total (with the rounds of its default job-rate limit, several a second,
    which the onstart handler above drops), beside the jobs it runs.
    """
    return list(dict.fromkeys(reduction_rows(REDUCTION_JOB[t]) for t in test_ids))


def test_params(test_id):
    """Everything of the tables that this test's reduction depends on, and
    its record's stamp (:func:`record_stamp`).

    Passed as params (not the table files as inputs) so that editing one row
    of tests.csv reduces that test's job again, not the whole campaign.
    """
    row = CAMPAIGN.test_row(test_id)
    # not its line: a row added above it changes nothing of this test
    out = {"row": {k: str(v) for k, v in row.items() if k != "line"}}
    specimen = _specimen_params(row.specimen)
    if specimen is not None:
        out["specimen"] = specimen
    out["setup"] = _setup_params(row.setup)
    out["error"] = str(CAMPAIGN.log.errors.get(test_id, ""))
    out["record"] = record_stamp(test_id)
    return out


# Once per specimen and setup, not per test: the params of every job are
# evaluated each time the DAG is (at the start and after each checkpoint).
@functools.cache
def _specimen_params(name):
    """The row of specimens.csv of a specimen as text, None when it has none."""
    known = name in set(CAMPAIGN.specimens.specimen)
    return {k: str(v) for k, v in CAMPAIGN.specimen(name).items()} if known else None


@functools.cache
def _setup_params(name):
    """The rows of setups.csv of a setup as text."""
    return CAMPAIGN.setup(name).astype(str).to_dict("records")


#: Categories of `snakemake --report`, one per stage of the workflow; the
#: report lists them by name, hence the numbers.
CATEGORY = {
    "qc": "1. Quality control",
    "kinematics": "2. Kinematics (Sect. 2)",
    "dissipation": "3. Energy dissipation (Sects. 3-4)",
    "diagnosis": "4. Model diagnosis",
    "limestone": "5. Limestone blocks",
    "maps": "6. Overturning maps (Sect. 5)",
}


def report_item(path, caption, stage, label, subcategory=None, **kw):
    """An output shown in the report, with workflow/report/<caption>.rst, in
    its stage's category, listed as label (a string: one 'result' column)
    or labels (a dict of columns, e.g. per wildcard)."""
    labels = {"result": label} if isinstance(label, str) else label
    return report(path, caption=f"../report/{caption}.rst", category=CATEGORY[stage],
                  subcategory=subcategory, labels=labels, **kw)


def report_figure(n, stage, what, subcategory=None):
    """Figure n of the paper (results/figures/figNN.png), with workflow/report/figNN.rst."""
    return report_item(res("figures", f"fig{n}.png"), f"fig{n}", stage, f"Fig. {int(n)}: {what}", subcategory)


def report_page(name, stage, what, subcategory=None):
    """The browsable page (results/report/<name>.html, rocklab.report.html) of
    a table or text, with workflow/report/<name>.rst."""
    return report_item(res("report", f"{name}.html"), name, stage, what, subcategory)


def campaign_outputs():
    """Everything of the campaign in raw_dir: reduction, QC, dissipation,
    diagnosis, their figures and report pages (no map, no limestone block)."""
    return qc_outputs() + dissipation_outputs() + figure_outputs() + diagnosis_outputs()


def all_outputs():
    return campaign_outputs() + limestone_outputs() + map_outputs() + calibrated_outputs()
