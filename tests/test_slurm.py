"""The workflow on a real single-node SLURM cluster, through the project's profile (workflow/profiles/slurm).

The fixture starts munged, slurmctld and slurmd on this host (.ci/run installs
Debian's slurm-wlm and munge); each test runs a target through the profile
and the same target locally, and compares what they wrote.  Without SLURM's
binaries or root, the module skips, saying which.
"""

import fcntl
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd
import pytest
import xarray as xr
import yaml

from rocklab.lab import virtual_lab

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
PROFILE = ROOT / "workflow" / "profiles" / "slurm"
PARTITION = "rocklab"
# slurm-wlm's compiled-in path: the jobstep executor runs each rule with a
# nested srun whose environment keeps no SLURM_* variable but the job's id,
# so SLURM_CONF cannot point it elsewhere.
SLURM_CONF = Path("/etc/slurm/slurm.conf")
MARK = "# rocklab test cluster (tests/test_slurm.py); removed when the tests end"
DAEMONS = ("munged", "slurmctld", "slurmd")
CLIENTS = ("sbatch", "squeue", "scancel", "sinfo", "srun")
# The cluster has no accounting database: the plugin follows its jobs with
# squeue (MinJobAge, 300 s by default, keeps an ended job visible), not
# sacct; unable to guess an account, it submits without one.  The first
# status check after 2 s instead of 40 s: the jobs here last seconds.
CLUSTER_OPTIONS = (
    "--slurm-status-command",
    "squeue",
    "--slurm-init-seconds-before-status-checks",
    "2",
)


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _slurm_conf(folder, munge_socket):
    """A slurm.conf of one node, this host as ``slurmd -C`` sees it (its cores and memory)."""
    node = subprocess.run(["slurmd", "-C"], capture_output=True, text=True, check=True).stdout.splitlines()[0]
    name = node.split()[0].removeprefix("NodeName=")
    return f"""{MARK}
ClusterName=rocklab
SlurmctldHost={name}(127.0.0.1)
SlurmUser=root
SlurmctldPort={_free_port()}
SlurmdPort={_free_port()}
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={munge_socket}
StateSaveLocation={folder}/state
SlurmdSpoolDir={folder}/spool
SlurmctldPidFile={folder}/slurmctld.pid
SlurmdPidFile={folder}/slurmd.pid
SlurmctldLogFile={folder}/slurmctld.log
SlurmdLogFile={folder}/slurmd.log
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
MinJobAge=300
{node} NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName={PARTITION} Nodes={name} Default=YES MaxTime=INFINITE State=UP
"""


def _stop(pid_file):
    """Stop the daemon of a pid file and wait until it has gone."""
    try:
        pid = int(pid_file.read_text())
    except (OSError, ValueError):
        return
    try:
        os.kill(pid, signal.SIGTERM)
        for _ in range(100):
            os.kill(pid, 0)
            time.sleep(0.1)
        os.kill(pid, signal.SIGKILL)
    except ProcessLookupError:
        pass


def _start_cluster(folder, started):
    """Start munged, slurmctld and slurmd with their state in folder, appending each one's pid file to started."""
    munge = folder / "munge"
    for sub in ("state", "spool", "munge"):
        (folder / sub).mkdir()
    # munged wants its key private; its socket's folder must be open to every user
    key = folder / "munge.key"
    key.write_bytes(os.urandom(1024))
    key.chmod(0o400)
    munge.chmod(0o755)
    pid_file = munge / "munged.pid"
    subprocess.run(
        ["munged", "--force", f"--key-file={key}", f"--socket={munge / 'munge.sock'}", f"--pid-file={pid_file}"]
        + [f"--log-file={munge / 'munged.log'}", f"--seed-file={munge / 'seed'}"],
        check=True,
        capture_output=True,
    )
    started.append(pid_file)
    SLURM_CONF.parent.mkdir(parents=True, exist_ok=True)
    SLURM_CONF.write_text(_slurm_conf(folder, munge / "munge.sock"))
    for daemon in ("slurmctld", "slurmd"):
        subprocess.run([daemon, "-f", str(SLURM_CONF)], check=True, capture_output=True)
        started.append(folder / f"{daemon}.pid")


@pytest.fixture(scope="module")
def slurm_cluster(tmp_path_factory):
    """A running one-node cluster: munged, slurmctld and slurmd, torn down after the module.

    One at a time on this host (its slurm.conf is the host's): a lock file
    makes a second pytest worker or session wait for the first's teardown.
    """
    if os.geteuid() != 0:
        pytest.skip("slurmd runs jobs as their user: starting the test cluster needs root")
    missing = [b for b in DAEMONS + CLIENTS if shutil.which(b) is None]
    if missing:
        pytest.skip(f"SLURM not installed ({', '.join(missing)} missing; .ci/run installs slurm-wlm and munge)")
    if not SNAKEMAKE.exists():
        pytest.skip("snakemake not installed beside this interpreter")
    folder = tmp_path_factory.mktemp("slurm")
    started = []
    with open(Path(tempfile.gettempdir()) / "rocklab-test-slurm.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if SLURM_CONF.exists() and MARK not in SLURM_CONF.read_text():
            pytest.skip(
                f"this host has a SLURM configuration of its own ({SLURM_CONF}); the test cluster would replace it"
            )
        try:
            try:
                _start_cluster(folder, started)
            except subprocess.CalledProcessError as exc:
                pytest.skip(f"a SLURM daemon did not start: {exc.cmd[0]}: {exc.stderr.decode()[-1000:]}")
            for _ in range(60):
                state = subprocess.run(["sinfo", "-h", "-o", "%T"], capture_output=True, text=True).stdout.strip()
                if state == "idle":
                    break
                time.sleep(0.5)
            else:
                logs = "\n".join((folder / f"{d}.log").read_text()[-1500:] for d in ("slurmctld", "slurmd"))
                pytest.skip(f"the test cluster's node never became idle (sinfo: {state!r}):\n{logs}")
            yield folder
        finally:
            if started:
                subprocess.run(["scancel", "--partition", PARTITION], capture_output=True)
            for pid_file in reversed(started):
                _stop(pid_file)
            SLURM_CONF.unlink(missing_ok=True)


def _profile_resources():
    """The profile's default resources, with the test cluster's partition: a
    --default-resources on the command line replaces the profile's whole list."""
    profile = yaml.safe_load((PROFILE / "config.yaml").read_text())
    return [f"{k}={v}" for k, v in profile["default-resources"].items()] + [f"slurm_partition={PARTITION}"]


def _config(folder, **config):
    """The workflow's config, the profile's maps.yaml and the test's keys, as --configfile takes them."""
    path = folder / "test.yaml"
    path.write_text(yaml.safe_dump(config))
    return ["--configfile", str(ROOT / "config" / "config.yaml"), str(PROFILE / "maps.yaml"), str(path)]


def _snakemake(target, workdir, config, *options):
    """The command of a run of target in its own working directory (.snakemake, SLURM logs)."""
    workdir.mkdir(parents=True, exist_ok=True)
    return [str(SNAKEMAKE), target, "--directory", str(workdir), *config, *options]


def _on_slurm(target, workdir, config):
    return _snakemake(
        target,
        workdir,
        config,
        "--profile",
        str(PROFILE),
        "--default-resources",
        *_profile_resources(),
        *CLUSTER_OPTIONS,
    )


def _run(cmd):
    run = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env={**os.environ, "PYTHONWARNINGS": "ignore"})
    assert run.returncode == 0, (run.stdout + run.stderr)[-4000:]
    return run.stdout + run.stderr


def _jobs(log):
    """What a run's log says it did: SLURM jobs submitted, jobs finished (local rules included)."""
    submitted, finished = log.count("has been submitted with SLURM jobid"), log.count("Finished jobid")
    return f"{submitted} SLURM jobs submitted, {finished} finished"


def _running_jobs():
    """SLURM job id -> comment (the plugin's ``rule_<name>[_wildcards_...]``) of the running jobs."""
    out = subprocess.run(["squeue", "-h", "-t", "RUNNING", "-o", "%i %k"], capture_output=True, text=True).stdout
    return dict(line.split(" ", 1) for line in out.splitlines() if line.strip())


def _kill_one_job(cmd):
    """Run cmd, scancel the first of its jobs that runs and every retry of it.

    Returns the killed SLURM job ids, the comment that names their rule, and the run's log.
    """
    run = subprocess.Popen(
        cmd,
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env={**os.environ, "PYTHONWARNINGS": "ignore"},
    )
    killed, rule = [], None
    while run.poll() is None:
        for jobid, comment in _running_jobs().items():
            if jobid not in killed and rule in (None, comment):
                rule = comment
                subprocess.run(["scancel", jobid], check=True)
                killed.append(jobid)
        time.sleep(0.5)
    log = run.stdout.read()
    assert run.returncode != 0, log[-4000:]
    return killed, rule, log


# What a map's attributes say of its run, not of the map: when it was written, how long it took.
RUN_ATTRS = ("history", "compute_s")


def _map(path):
    with xr.open_dataset(path) as ds:
        return ds.load().drop_attrs(deep=False).assign_attrs({k: v for k, v in ds.attrs.items() if k not in RUN_ATTRS})


def _map_files(results):
    return sorted(p.relative_to(results) for p in (results / "maps").rglob("*") if p.is_file())


def test_maps_on_slurm_survive_a_killed_job_and_equal_the_local_maps(slurm_cluster, tmp_path, record_property):
    # two records, one job each (the profile's maps.yaml), two threads: the node's two cores
    config = _config(
        tmp_path, raw_dir=str(ROOT / "raw" / "campaign"), maps={"records": ["Pac164", "RRS228"], "n": 3, "threads": 2}
    )
    local, cluster = tmp_path / "local", tmp_path / "cluster"
    _run(_snakemake("maps", tmp_path / "wd-local", config + ["--config", f"results_dir={local}"], "--cores", "2"))
    on_slurm = _on_slurm("maps", tmp_path / "wd-slurm", config + ["--config", f"results_dir={cluster}"])
    killed, rule, log = _kill_one_job(on_slurm)
    # the profile's retries: 1 submits a killed job once more; killed again, the run stops, naming it
    assert len(killed) == 2, log[-4000:]
    for jobid in killed:
        assert f"SLURM-job '{jobid}' failed, SLURM status is: 'CANCELLED'" in log
    assert f"Error in rule {rule.removeprefix('rule_').split('_wildcards_')[0]}" in log
    assert "Exiting because a job execution failed" in log
    rerun = _run(on_slurm)
    assert "has been submitted with SLURM jobid" in rerun and "Complete log" in rerun
    # shown at the end of the run (tests/conftest.py): what the cluster did, in CI's output too
    record_property(
        "slurm", f"maps: {_jobs(log)}, SLURM jobs {' and '.join(killed)} cancelled; the rerun: {_jobs(rerun)}"
    )
    files = _map_files(local)
    # five maps per record, the three tables, and the list of maps each job wrote (one job per record)
    assert files == _map_files(cluster) and len(files) == 2 * 5 + 3 + 2
    for name in files:
        if name.suffix == ".nc":
            xr.testing.assert_identical(_map(local / name), _map(cluster / name))
        else:
            assert (local / name).read_bytes() == (cluster / name).read_bytes(), name
    for name in ("figures/fig21.png", "report/map_summary.html"):
        assert (cluster / name).stat().st_size > 0


def test_campaign_on_slurm_writes_the_tables_of_the_local_run(slurm_cluster, tmp_path, record_property):
    folder = tmp_path / "campaign"
    virtual_lab.write_campaign(folder, virtual_lab.default_plan(3, seed=3), seed=3)
    config = _config(tmp_path, raw_dir=str(folder), figures={"fig9_specimen": "1a"})
    local, cluster = tmp_path / "local", tmp_path / "cluster"
    _run(_snakemake("campaign", tmp_path / "wd-local", config + ["--config", f"results_dir={local}"], "--cores", "2"))
    log = _run(_on_slurm("campaign", tmp_path / "wd-slurm", config + ["--config", f"results_dir={cluster}"]))
    assert "has been submitted with SLURM jobid" in log
    record_property("slurm", f"campaign: {_jobs(log)}")
    tables = sorted(p.name for p in local.glob("*.csv"))
    assert {"qc.csv", "tests.csv", "impacts.csv", "series.csv"} <= set(tables)
    assert tables == sorted(p.name for p in cluster.glob("*.csv"))
    for name in tables:
        pd.testing.assert_frame_equal(pd.read_csv(local / name), pd.read_csv(cluster / name), obj=name)
        assert (local / name).read_bytes() == (cluster / name).read_bytes(), name
