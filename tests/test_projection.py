"""The cluster projections of docs/performance.md (rocklab.benchmarks), from measured per-job costs."""

from pathlib import Path

import pytest

from rocklab.benchmarks import (
    CAMPAIGN_FACTOR,
    CLUSTER_NODES,
    CORES_PER_NODE,
    MAP_CELLS,
    campaign_projection,
    maps_projection,
    slurm_profile,
)

PROFILE = {"mem_mb": 2000, "runtime": 30, "cpus_per_task": 1, "jobs": 100, "maps_threads": 4, "maps_records_per_job": 1}


def _run(n, reduce_s, diagnosis_s):
    return {
        "n_tests": n,
        "peak_rss_process_mb": 400.0,
        "stage_s": {"reduce": reduce_s, "diagnosis": diagnosis_s},
        "stage_jobs": {"reduce": 3, "diagnosis": 3},
        "stage_longest_s": {"reduce": reduce_s / 3, "diagnosis": 0.9 * diagnosis_s},
    }


def test_the_campaign_grows_on_the_line_through_the_two_sizes():
    scale = {"runs": [_run(100, 12.0, 5.0), _run(1000, 102.0, 50.0)]}
    p = campaign_projection(scale, PROFILE, n_embedded=10, max_tests_per_job=250)
    n = CAMPAIGN_FACTOR * 10
    assert p["n_tests"] == n
    assert p["stages"]["reduce"]["job_s"] == pytest.approx(2.0 + 0.1 * n)
    assert p["stages"]["reduce"]["jobs"] == -(-n // 250)
    # a stage of a fixed number of jobs: its longest job grows with it, and bounds its wall time
    assert p["stages"]["diagnosis"]["longest_s"] == pytest.approx(0.9 * 0.05 * n)
    slots = CLUSTER_NODES[-1] * CORES_PER_NODE
    reduce_s, jobs = 2.0 + 0.1 * n, -(-n // 250)
    assert p["wall_s"][-1] == pytest.approx(max(reduce_s / slots, reduce_s / jobs) + 0.9 * 0.05 * n)
    assert p["wall_s"][0] == pytest.approx(max(reduce_s / CORES_PER_NODE, reduce_s / jobs) + 0.9 * 0.05 * n)
    assert p["wall_s"] == sorted(p["wall_s"], reverse=True)
    assert p["fits_mem"]


def test_the_maps_grow_with_their_cells_and_pack_in_waves():
    maps = {"all_maps_records": ["a", "b"], "all_maps_cpu_s": 10.0, "all_maps_count": 10, "grid": [100, 100]}
    p = maps_projection(maps, PROFILE)
    assert p["map_cpu_s"] == pytest.approx(1.0 * MAP_CELLS**2 / 100**2)
    assert p["cpu_s"] == pytest.approx(p["map_cpu_s"] * 2 * 14)
    assert p["jobs"] == 4
    # the longest job: a record's 9 calibrated maps on 4 threads; 4 jobs fit on one node of 32 cores at once
    assert p["wall_s"][0] == pytest.approx(p["map_cpu_s"] * 9 / 4)


def test_the_profile_is_read_from_the_checkout():
    profile = slurm_profile(Path(__file__).resolve().parents[1])
    assert profile["cpus_per_task"] >= 1 and profile["maps_threads"] <= CORES_PER_NODE
