"""Results written whole or not at all, and a full disk said plainly (rocklab.disk): the
writers' faults injected, for machines where no small filesystem can be mounted
(tests/test_interrupt.py fills one where it can)."""

import errno
import pickle
import shutil

import numpy as np
import pytest
import xarray as xr

import rocklab.disk
import rocklab.io
from rocklab.io import write_netcdf

# --- writes on a full disk ------------------------------------------------------------------


def _full_disk(monkeypatch, free=0):
    """The disk of every folder reports ``free`` bytes: a fault injected where no small filesystem can be mounted."""
    usage = shutil.disk_usage(".")._replace(free=free)
    monkeypatch.setattr(rocklab.disk.shutil, "disk_usage", lambda folder: usage)


def test_a_write_that_fails_leaves_neither_the_file_nor_a_temporary_one(tmp_path):
    with pytest.raises(KeyError), rocklab.disk.atomic_output(tmp_path / "a.csv") as tmp:
        tmp.write_text("half")
        raise KeyError("the writer's own error")
    assert list(tmp_path.iterdir()) == []


def test_a_killed_writer_s_temporary_file_goes_with_the_next_write(tmp_path):
    (tmp_path / ".a.csv.k3j9x_2q.tmp").write_text("left by a killed job")
    (tmp_path / ".a.csv.bak.abcdefgh.tmp").write_text("another file's, being written")
    rocklab.disk.write_text(tmp_path / "a.csv", "x\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == [".a.csv.bak.abcdefgh.tmp", "a.csv"]


def test_no_space_names_the_file_and_the_space_it_needed(tmp_path, monkeypatch):
    def enospc(self, data):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(rocklab.disk.Path, "write_bytes", enospc)
    _full_disk(monkeypatch, free=1200)
    with pytest.raises(rocklab.disk.NoSpace) as err:
        rocklab.disk.write_text(tmp_path / "qc.csv", "x" * 2_500_000)
    assert err.value.errno == errno.ENOSPC and err.value.needed == 2_500_000 and err.value.free == 1200
    assert str(err.value).startswith(
        f"no space left to write {tmp_path / 'qc.csv'}: it needs up to 2.5 MB, 1.2 kB free"
    )
    assert list(tmp_path.iterdir()) == []
    assert pickle.loads(pickle.dumps(err.value)).path == err.value.path


def test_a_netcdf_library_error_on_a_full_disk_is_no_space(tmp_path, monkeypatch):
    """netCDF-C reports a full disk as a bare HDF error: the free space tells."""
    ds = xr.Dataset({"theta": ("time", np.zeros(1000))}, coords={"time": np.arange(1000.0)})

    def hdf_error(*args, **kwargs):
        raise RuntimeError("NetCDF: HDF error")

    monkeypatch.setattr(rocklab.io, "_write_variables", hdf_error)
    with pytest.raises(RuntimeError, match="HDF error") as err:
        write_netcdf(ds, tmp_path / "t.nc")
    assert not isinstance(err.value, rocklab.disk.NoSpace)  # room enough: not a full disk
    _full_disk(monkeypatch)
    with pytest.raises(rocklab.disk.NoSpace) as err:
        write_netcdf(ds, tmp_path / "t.nc")
    assert err.value.path == tmp_path / "t.nc" and err.value.needed == ds.nbytes
    assert list(tmp_path.iterdir()) == []


def test_an_error_of_another_kind_is_not_taken_for_a_full_disk(tmp_path, monkeypatch):
    _full_disk(monkeypatch)
    with pytest.raises(ValueError), rocklab.disk.atomic_output(tmp_path / "a.csv"):
        raise ValueError("a bug, not the disk")


def test_a_job_log_closed_on_a_full_disk_loses_its_lines_without_a_traceback(tmp_path):
    """A map job logs each record to its own file in turn (rocklab.io.setup_logging): closing the
    previous one on a full disk must not raise under the job's one-line stop."""

    class FullStream:
        def write(self, text):
            return len(text)

        def flush(self):
            raise OSError(errno.ENOSPC, "No space left on device")

        def close(self):
            self.flush()

    handler = rocklab.io._JobLog(tmp_path / "job.log", mode="w")
    handler.stream.close()
    handler.stream = FullStream()
    handler.close()
    assert handler.stream is None
    other = rocklab.io._JobLog(tmp_path / "other.log", mode="w")
    other.stream.close()
    other.stream = FullStream()
    other.stream.flush = lambda: (_ for _ in ()).throw(OSError(errno.EACCES, "Permission denied"))
    with pytest.raises(OSError, match="Permission denied"):
        other.close()
