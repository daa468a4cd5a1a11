# Stage 1: each test's raw record to its wall motion (reader, channel health,
# four-DOF kinematics, validity by the lab's rules), one netCDF per test, and
# the motion extracted from it (release, impacts, peaks), stored inside it for the
# dissipation tables and the diagnosis; and per job the attributes of its tests'
# QC rows (results/reduction/<job>.json).
#
# Whole specimens packed into jobs of at most reduction.max_tests_per_job
# tests (a larger specimen cut into parts of its own), and one job for the
# tests refused at the door, not one per test or per series: a job spends
# longer starting Python and importing the library (about 2 s of CPU) than
# reducing thirty tests.


# A job's tests are the files of its folder, its declared output (a rule's
# outputs are patterns of its wildcards, and a job writes as many netCDF
# files as it has tests): Snakemake removes the folder before the job runs
# and when it fails, and a rule that reads a test takes its job's folder as
# input (reduced_inputs).  A file deleted from the folder, or any output
# truncated, is found by the check of the jobs' manifests before each run
# (rocklab.jobs.clear_damage, common.smk), which has the job run again.  A job's
# tests are its params: a test added to it reduces it again (the params
# trigger; not under --rerun-triggers mtime alone).
rule reduce:
    output:
        tests=directory(res("tests", "{job}")),
        rows=res("reduction", "{job}.json"),
        dissipation=res("reduction", "{job}.dissipation.json"),
    log:
        res("logs", "reduce", "{job}.log"),
    benchmark:
        res("benchmarks", "reduce", "{job}.tsv")
    wildcard_constraints:
        job=one_of(REDUCTION_JOBS),
    priority: lambda wildcards: reduction_priority(wildcards.job)
    params:
        tests=lambda wildcards: {t: test_params(t) for t in REDUCTION_JOBS[wildcards.job]},
        raw_dir=config["raw_dir"],
        options={"channels": config["channels"], "validity": config["validity"]},
    script:
        "../../scripts/reduce_tests.py"


# The accuracy of each instrument (transducers, motion capture, inertial) at
# the labs' sampling rates, measured on virtual-lab walls against their truth
# (rocklab.lab.accuracy): the numbers of docs/instruments.md. No input: the
# walls are the virtual lab's, whatever the campaign.
rule instrument_accuracy:
    output:
        docs_summary=res("summaries", "instruments.json"),
    log:
        res("logs", "instrument_accuracy.log"),
    benchmark:
        res("benchmarks", "instrument_accuracy.tsv")
    priority: PRIORITY["long_leaves"]
    params:
        n_tests=config["instruments"]["accuracy_tests"],
    script:
        "../../scripts/instrument_accuracy.py"
