# Paths, the campaign's test list, its jobs (reduction, diagnosis), the
# per-test parameters that decide when a test must be reduced again, the
# targets and the rules' input functions.
import functools
import re
import sys
from pathlib import Path

from snakemake.exceptions import WorkflowError

from rocklab.config import check_names, check_paths, check_writable, recorded_path
from rocklab.jobs import clear_damage, damaged
from rocklab.lab.campaign import UNREADABLE, open_campaign
from rocklab.lab.hierarchy import thickness_of_walls, walls_of_series, walls_of_specimens
from rocklab.seismic import calibrated
from rocklab.seismic.accelerograms import accelerogram_dir, read_manifest
from rocklab.shake_table.asu_data import check_dir

# config is validated by the Snakefile, every default filled in from
# workflow/schemas/config.schema.yaml: the rules read it without defaults.
check_paths(config["raw_dir"], config["results_dir"])
# before any job starts: a folder a job could not write in is refused, named
check_writable(config["results_dir"])
RAW = Path(config["raw_dir"])
RESULTS = Path(config["results_dir"])
#: Snakemake's options that run no job (a dry run, a report, a lint, a listing,
#: a graph): under them a damaged result is said, not cleared.
RUNS_NO_JOB = {"-n", "--dry-run", "--dryrun", "--report", "--lint", "-l", "--list-rules", "--list-target-rules"}
RUNS_NO_JOB |= {"-S", "--summary", "-D", "--detailed-summary", "--dag", "--rulegraph", "--filegraph", "--d3dag"}
RUNS_NO_JOB |= {"--unlock", "--cleanup-metadata", "--list-changes", "--lc", "--list-untracked", "--lt"}
RUNS_NO_JOB |= {"--delete-all-output", "--delete-temp-output", "--containerize", "--export-cwl"}


def runs_jobs(argv):
    """Whether a Snakemake command line may run jobs (a cluster of short flags with n is a dry run)."""
    return not any(a in RUNS_NO_JOB or re.fullmatch(r"-[A-Za-z]*n[A-Za-z]*", a) for a in argv)


# Results damaged since their job wrote them (a file deleted from a folder
# output, any output truncated or replaced, or gone while what was made from
# it stays, which Snakemake alone leaves as it is): that job's outputs and
# every output made from them are removed, so that Snakemake makes them
# again, and nothing else (rocklab.jobs).  In the main process of a run
# that runs jobs only (a cluster job parses this file too), and not while
# another run holds this working directory's lock or a job of another run
# writes in the results folder.
if workflow.is_main_process and not runs_jobs(sys.argv[1:]):
    for damage in damaged(RESULTS):
        print(f"rocklab: {RESULTS / damage.file}: {damage.problem}; its job would run again", file=sys.stderr)
elif workflow.is_main_process and not any(Path(".snakemake", "locks").glob("*")):
    cleared = clear_damage(RESULTS)
    if cleared is None:
        print(f"rocklab: a job of another run is writing in {RESULTS}: damaged results not looked for", file=sys.stderr)
    for c in cleared or []:
        print(f"rocklab: {RESULTS / c.damage.file}: {c}", file=sys.stderr)
# Every row checked at the door (docs/raw-format.md): a refused row is a row
# of qc.csv, and no id or path of the tables names a file outside the two folders.
CAMPAIGN = open_campaign(RAW)
#: The wall of each specimen (the unit of a wall's properties, rocklab.lab.hierarchy).
WALL_OF_SPECIMEN = walls_of_specimens(CAMPAIGN)
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
#: The series of each diagnosis job: whole series packed up to diagnosis.max_tests_per_job tests
#: (the tests refused at the door are in no series: they have no diagnosis).
#: The wall of each series (the unit of a boundary condition's pooled parameters).
WALL_OF_SERIES = walls_of_series(CAMPAIGN)
#: The thickness of each wall [m] (the size the findings were measured at, rocklab.seismic.calibrated).
WALL_THICKNESS = thickness_of_walls(CAMPAIGN)
DIAGNOSIS_JOBS = CAMPAIGN.diagnosis_jobs(config["diagnosis"]["max_tests_per_job"])


# Scheduling: on few cores Snakemake starts the selectable jobs of highest
# priority first.  The campaign's chain (reduction, diagnosis, its
# checkpoint) leads to the longest path to the end, through the calibrated
# maps; the maps come next (the paper's, independent of the campaign, fill
# the cores the chain leaves idle), figures and pages last.  With equal
# priorities a map job started first could hold a core for most of the
# reduction and leave the diagnosis to the end.  Of the jobs only the docs
# wait for, the long ones start first (the diagnosis' figures, the
# instruments' accuracy, about 10 s each): last, each ran alone on one core.
PRIORITY = {"campaign_chain": 20, "maps": 10, "long_leaves": 5}
#: The diagnosis job of each series.
DIAGNOSIS_JOB = {s: job for job, series in DIAGNOSIS_JOBS.items() for s in series}
_SERIES_OF_TEST = {t: s for s, ids in TESTS_BY_SERIES.items() for t in ids}


def diagnosis_priority(job):
    """A diagnosis job's priority in the campaign's chain: the more tests, the sooner.

    The largest series of a large campaign take longest, and the last job
    to start ends the diagnosis: the largest first, the others fill the
    other cores.  Between the chain's priority and the next integer.
    """
    n = sum(len(TESTS_BY_SERIES[s]) for s in DIAGNOSIS_JOBS[job])
    return PRIORITY["campaign_chain"] + n / (len(_SERIES_OF_TEST) + 1)


def reduction_priority(job):
    """A reduction job's priority: that of the largest diagnosis job that waits for it
    (:func:`diagnosis_priority`), so that the largest series are reduced first."""
    waiting = {DIAGNOSIS_JOB[_SERIES_OF_TEST[t]] for t in REDUCTION_JOBS[job] if t in _SERIES_OF_TEST}
    return max(map(diagnosis_priority, waiting), default=PRIORITY["campaign_chain"])


def res(*parts):
    return str(RESULTS.joinpath(*parts))


def one_of(names):
    """A wildcard constraint matching exactly these names (a job's name, a boundary condition)."""
    return "|".join(re.escape(str(n)) for n in names)


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
    job-rate limit, profiles/default) its own CPU grew
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


def test_file(test_id):
    """A reduced test's netCDF file, in the folder of its reduction job (rule reduce)."""
    return res("tests", REDUCTION_JOB[test_id], f"{test_id}.nc")


def reduced_inputs(test_ids):
    """The input of a job over many reduced tests: the folders of their
    reduction jobs (rule reduce), not the tests' netCDF files in them
    (:func:`test_file`, passed as params).

    Snakemake stats every input of every job waiting for a core at each
    scheduling round: listed file by file, the 2,500 netCDF inputs of the
    QC, dissipation and diagnosis jobs cost Snakemake's own process some
    20 s of CPU of a 35 s total (with the rounds of its job-rate limit,
    several a second, see profiles/default), beside the jobs it runs.
    """
    return expand(rules.reduce.output.tests, job=list(dict.fromkeys(REDUCTION_JOB[t] for t in test_ids)))


def reduced_rows(test_ids):
    """The rows files (the attributes of their QC rows) of the reduction jobs of ``test_ids``."""
    return expand(rules.reduce.output.rows, job=list(dict.fromkeys(REDUCTION_JOB[t] for t in test_ids)))


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
    return report(
        path, caption=f"../report/{caption}.rst", category=CATEGORY[stage], subcategory=subcategory, labels=labels, **kw
    )


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
    return QC_OUTPUTS + DISSIPATION_OUTPUTS + FIGURE_OUTPUTS + DIAGNOSIS_OUTPUTS


def all_outputs():
    return campaign_outputs() + LIMESTONE_OUTPUTS + MAP_OUTPUTS + CALIBRATED_OUTPUTS


# Input functions of the stages' rules (`snakemake --lint` wants a rule file
# without functions).  A test's netCDF file and a map lie in the folder that
# their job declares as its output (a job writes a number of them that its
# wildcards do not give): a rule that reads one takes the folder as input,
# the file as a param.


def kinematics_sample(wildcards):
    """The reduced test that Figs. 6, 8 and 9 draw, once the QC table (after
    every reduction job) is written: its id (its file: :func:`test_file`)."""
    from rocklab.io import valid_test_ids

    qc = checkpoints.qc_table.get().output.qc
    if KINEMATICS_SAMPLE:
        return KINEMATICS_SAMPLE
    valid = valid_test_ids(qc)
    if not valid:
        # every later stage needs a reduced test: stop here, with the table that says why
        raise WorkflowError(f"no test of the campaign is valid, nothing to reduce further: see {qc}, reject_reason")
    # Figs. 6 and 9a draw a transducer and Eq. 8: a test of transducers where the campaign has one
    import pandas as pd

    table = pd.read_csv(qc, usecols=["test_id", "instrument"], dtype=str, keep_default_na=False)
    transducers = set(table.test_id[table.instrument == "transducers"])
    return next((t for t in valid if t in transducers), valid[0])


def fig20_sample_test(wildcards):
    """The reduced test that Fig. 20a draws (none without a one-sided test with a
    monitor), once the dissipation tables (after every reduction job) are
    written: a list of its id, or an empty one."""
    import pandas as pd
    from rocklab.plots.dissipation import fig20_sample

    tests = checkpoints.dissipation_tables.get().output.tests
    test_id = FIG20_SAMPLE or fig20_sample(pd.read_csv(tests))
    return [test_id] if test_id else []


def map_path(record, model):
    """The paper's map of a record, in the folder of its map job (rule overturning_maps)."""
    return res("maps", f"records-{MAP_BATCH[record]}", f"{record}__{model}.nc")


def calibrated_map_folder(record):
    """The folder of the calibrated maps of a record's map job (rule calibrated_maps)."""
    return res("maps", "calibrated", f"records-{MAP_BATCH[record]}")


def record_path(record):
    """The shipped file of a record, so that replacing it recomputes its maps."""
    return recorded_path(accelerogram_dir() / MANIFEST.set_index("record").loc[record, "file"])


def calibrated_map_names():
    """The calibrated walls of the campaign's diagnosis (a checkpoint), and the
    paper's e-alone models of the boundaries they calibrate."""
    names = calibrated.model_names(checkpoints.diagnosis.get().output.json)
    boundaries = {calibrated.parse_name(n)[0] for n in names}
    return names, [calibrated.E_ALONE[b] for b in calibrated.PREFIX if b in boundaries]


def calibrated_map_inputs(wildcards):
    """The maps of the paper's e-alone models and of the calibrated walls, for
    the boundaries the campaign's diagnosis calibrates."""
    names, e_alone = calibrated_map_names()
    return [map_path(r, m) for r in MAP_RECORDS for m in e_alone] + [
        str(Path(calibrated_map_folder(r), f)) for r in MAP_RECORDS for f in sorted(f"{r}__{n}.nc" for n in names)
    ]


def calibrated_map_batches(wildcards):
    """The folders of the map jobs that write :func:`calibrated_map_inputs`."""
    names, e_alone = calibrated_map_names()
    batches = expand(rules.overturning_maps.output, batch=MAP_BATCHES) if e_alone else []
    return batches + (expand(rules.calibrated_maps.output, batch=MAP_BATCHES) if names else [])


def shake_table_data(wildcards):
    """tests.csv and geometry.json of shake_table_dir; a missing folder stops the target, naming the key."""
    try:
        folder = check_dir(ST_DIR)
    except FileNotFoundError as exc:
        raise WorkflowError(str(exc)) from None
    return [recorded_path(folder / "tests.csv"), recorded_path(folder / "geometry.json")]
