"""netCDF writing and reading of rocklab.io against xarray's own.

:func:`rocklab.io.write_netcdf` writes the kinds of variable rocklab stores
through netCDF4 directly and anything else through xarray;
:func:`rocklab.io.read_dataset` reads with netCDF4 directly.  Each must give
what xarray gives: the same file to every reader, the same dataset back.
"""

import netCDF4
import numpy as np
import pytest
import xarray as xr

import rocklab.io
from rocklab.io import read_dataset, valid_tests, write_netcdf


def every_kind(n_impacts=3):
    """A dataset with every kind of variable and attribute rocklab writes."""
    t = np.arange(6) / 400
    theta = np.array([0.1, np.nan, 0.05, -0.0, 1e-300, np.inf])
    return xr.Dataset(
        {
            "theta": ("time", theta, {"long_name": "rotation", "units": "rad"}),
            "n_channels": ("time", np.arange(6, dtype=np.int64), {"units": "1"}),
            "converged": ("time", np.array([True, False, True, True, False, True]), {"flag_meanings": "no yes"}),
            "used": ("channel", np.array([0, 1, 1], np.int8), {"flag_values": np.array([0, 1], np.int8)}),
            "status": ("channel", np.array(["ok", "", "répété"], object), {"long_name": "état"}),
            "role": ("channel", np.array(["monitor", "in_plane", "x"])),
            "raw": (("time", "channel"), np.where(np.arange(18).reshape(6, 3) % 5, 1.5, np.nan)),
            "single": ("channel", np.array([1, 2, 3], np.float32)),
            "count": ((), np.int64(7)),
            "ratio": ((), 0.25),
            "label": ((), "one"),
            "e": ("impact", np.linspace(0.9, 0.8, n_impacts)),
        },
        coords={"time": ("time", t, {"units": "s"}), "channel": ("channel", np.array([0, 1, 4]))},
        attrs={
            "title": "every kind",
            "note": "",
            "n": 3,
            "valid": np.int64(1),
            "alpha": 0.1,
            "float32": np.float32(1.5),
            "int8": np.int8(-2),
            "nan": np.nan,
            "list": [1, 2],
            "floats": (0.5, 1.5),
            "texts": ["a", "bc"],
            "array": np.array([1.0, 2.0]),
            "history": "made by hand",
        },
    )


def force_xarray(monkeypatch):
    """Have write_netcdf hand every dataset to xarray."""
    monkeypatch.setattr(rocklab.io, "_stored_variable", lambda var: None)


def same(a, b):
    """Equal in type, dtype, shape and every bit (NaN where NaN)."""
    if type(a) is not type(b):
        return False
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype != b.dtype or a.shape != b.shape:
        return False
    if a.dtype.kind == "f":
        return np.array_equal(a.view(f"u{a.itemsize}"), b.view(f"u{b.itemsize}"))
    return np.array_equal(a, b)


def assert_same_datasets(a, b, history=True):
    """Identical, in the same order, values bit for bit, attributes of the same types."""
    xr.testing.assert_identical(a.drop_attrs(deep=False), b.drop_attrs(deep=False))
    assert list(a.variables) == list(b.variables) and list(a.coords) == list(b.coords)
    keys = [k for k in a.attrs if history or k != "history"]
    assert keys == [k for k in b.attrs if history or k != "history"]
    for k in keys:
        assert same(a.attrs[k], b.attrs[k]), k
    for name in a.variables:
        assert same(a[name].values, b[name].values), name
        assert list(a[name].attrs) == list(b[name].attrs), name
        assert all(same(v, b[name].attrs[k]) for k, v in a[name].attrs.items()), name


def storage(path):
    """What a file holds to netCDF4: dimensions, variables with their storage, attributes."""
    with netCDF4.Dataset(path) as nc:
        nc.set_auto_maskandscale(False)
        nc.set_auto_chartostring(False)
        return {
            "model": nc.data_model,
            "dims": [(d.name, d.size) for d in nc.dimensions.values()],
            "variables": [
                (
                    name,
                    v.dtype,
                    v.dimensions,
                    v.filters(),
                    v.chunking(),
                    v.endian(),
                    v[...].tobytes(),
                    [(k, repr(v.getncattr(k))) for k in v.ncattrs()],
                )
                for name, v in nc.variables.items()
            ],
            "attrs": [(k, repr(nc.getncattr(k))) for k in nc.ncattrs() if k != "history"],
        }


@pytest.mark.parametrize("n_impacts", [3, 0])
def test_the_direct_writer_writes_what_xarray_writes(tmp_path, monkeypatch, n_impacts):
    ds = every_kind(n_impacts)
    write_netcdf(ds, tmp_path / "direct.nc")
    with monkeypatch.context() as m:
        force_xarray(m)
        write_netcdf(ds, tmp_path / "xarray.nc")
    assert storage(tmp_path / "direct.nc") == storage(tmp_path / "xarray.nc")
    a, b = xr.load_dataset(tmp_path / "direct.nc"), xr.load_dataset(tmp_path / "xarray.nc")
    assert_same_datasets(a, b, history=False)
    for name in a.variables:
        keep = ("dtype", "zlib", "complevel", "shuffle", "contiguous", "chunksizes", "_FillValue", "char_dim_name")
        assert [k for k in keep if k in a[name].encoding] == [k for k in keep if k in b[name].encoding], name
        assert all(same(a[name].encoding[k], b[name].encoding[k]) for k in keep if k in a[name].encoding), name


def test_a_written_dataset_reads_back_as_it_was(tmp_path):
    ds = every_kind()
    write_netcdf(ds, tmp_path / "a.nc")
    back = xr.load_dataset(tmp_path / "a.nc")
    assert back.attrs["history"].startswith("made by hand\n") and "rocklab" in back.attrs["history"]
    assert back.attrs["Conventions"] == "CF-1.8" and "Conventions" not in ds.attrs
    xr.testing.assert_identical(back.drop_attrs(), ds.drop_attrs())
    assert back.converged.dtype == bool and back.status.values.tolist() == ["ok", "", "répété"]
    assert np.isnan(back.theta.encoding["_FillValue"])
    assert "_FillValue" not in back.n_channels.encoding and not back.converged.encoding.get("zlib", False)


@pytest.mark.parametrize("direct", [True, False])
def test_only_what_zlib_packs_is_compressed(tmp_path, monkeypatch, direct):
    rng = np.random.default_rng(0)
    n = 4000
    ds = xr.Dataset(
        {
            # a rotation solved at full precision: zlib keeps ~90 % of it
            "theta": ("time", np.cumsum(rng.normal(0, 1e-4, n))),
            # transducer readings of three decimals, at rest for the first half
            "raw": ("time", np.round(np.r_[np.zeros(n // 2), rng.normal(0, 5, n - n // 2)], 3)),
            "n_channels": ("time", np.full(n, 5, np.int64)),
            # a few numbers (one per channel), which zlib would pack but not pay for their chunk index
            "gain": ("channel", np.ones(6)),
        },
        coords={"time": ("time", np.arange(n) / 400)},
    )
    if not direct:
        force_xarray(monkeypatch)
    write_netcdf(ds, tmp_path / "a.nc")
    with netCDF4.Dataset(tmp_path / "a.nc") as nc:
        zlib = {name: v.filters()["zlib"] for name, v in nc.variables.items()}
    assert zlib == {"theta": False, "raw": True, "n_channels": True, "gain": False, "time": True}
    xr.testing.assert_identical(xr.load_dataset(tmp_path / "a.nc").drop_attrs(), ds)


def test_read_dataset_gives_what_xarray_gives(tmp_path):
    write_netcdf(every_kind(), tmp_path / "a.nc")
    ds = xr.load_dataset(tmp_path / "a.nc")
    assert_same_datasets(read_dataset(tmp_path / "a.nc"), ds)
    for names in (["theta"], ["status", "count"], ["raw"], ["e"]):
        assert_same_datasets(read_dataset(tmp_path / "a.nc", names), ds[names])
    assert list(read_dataset(tmp_path / "a.nc", ["theta"]).variables) == ["theta", "time"]
    # a coordinate stored before the data (as in a reduced test) comes after them, as in xarray
    write_netcdf(
        xr.Dataset({"phi": ("time", [1.0]), "time": ("time", [0.0]), "theta": ("time", [2.0])}), tmp_path / "b.nc"
    )
    assert_same_datasets(read_dataset(tmp_path / "b.nc"), xr.load_dataset(tmp_path / "b.nc"))


#: Variables that xarray decodes beyond what write_netcdf writes directly: times,
#: times as numbers with units, durations' units, packing, a fill value, the text
#: of another encoding, auxiliary coordinates.
DECODED_BY_XARRAY = {
    "when": ("time", np.arange(6).astype("datetime64[D]")),
    "late": ("channel", np.arange(3.0), {"units": "seconds since 2000-01-01"}),
    "span": ("channel", np.arange(3.0), {"units": "seconds"}),
    "scaled": ("time", np.arange(6.0), {}, {"scale_factor": 0.5, "dtype": "int16", "_FillValue": -1}),
    "filled": ("channel", np.array([1.0, np.nan, 3.0]), {}, {"_FillValue": -9.0}),
    "latin": ("channel", np.array(["é", "b", "c"]), {}, {"dtype": "S1", "_Encoding": "latin-1"}),
    "aux": None,
}


@pytest.mark.parametrize("name", DECODED_BY_XARRAY)
def test_read_dataset_leaves_what_xarray_decodes_otherwise_to_it(tmp_path, name):
    ds = every_kind()
    if name == "aux":
        # one named by the variables on its dimension, one by the file (none on "other")
        ds = ds.assign_coords(aux=("channel", np.array([7, 8, 9])), extra=("other", [1, 2]))
        ds = ds.assign(near=("channel", np.ones(3)))
        name = "near"
    else:
        ds = ds.assign({name: DECODED_BY_XARRAY[name]})
    ds.to_netcdf(tmp_path / "x.nc", engine="netcdf4")
    back = xr.load_dataset(tmp_path / "x.nc")
    assert_same_datasets(read_dataset(tmp_path / "x.nc"), back)
    assert_same_datasets(read_dataset(tmp_path / "x.nc", [name]), back[[name]])
    assert_same_datasets(read_dataset(tmp_path / "x.nc", ["theta"]), back[["theta"]])


def test_read_dataset_names_the_variables_a_file_lacks(tmp_path):
    write_netcdf(every_kind(), tmp_path / "x.nc")
    with pytest.raises(KeyError, match=r"x\.nc: no variable omega"):
        read_dataset(tmp_path / "x.nc", ["theta", "omega"])


@pytest.mark.parametrize("extra", ["times", "auxiliary coordinate"])
def test_a_dataset_outside_the_direct_kinds_goes_through_xarray(tmp_path, extra):
    if extra == "times":
        ds = every_kind().assign(when=("time", np.arange(6).astype("datetime64[s]")))
    else:
        ds = every_kind().assign_coords(aux=("channel", np.array([7, 8, 9])))
    write_netcdf(ds, tmp_path / "a.nc")
    back = xr.load_dataset(tmp_path / "a.nc")
    xr.testing.assert_identical(back.drop_attrs(), ds.drop_attrs())


@pytest.mark.parametrize("value", [None, {"a": 1}, True])
def test_an_attribute_netcdf_cannot_hold_is_named(tmp_path, value):
    with pytest.raises(TypeError, match="attribute 'bad'"):
        write_netcdf(every_kind().assign_attrs(bad=value), tmp_path / "a.nc")
    with pytest.raises(TypeError, match=r"a\.nc, variable theta: attribute 'bad'"):
        ds = every_kind()
        ds.theta.attrs["bad"] = value
        write_netcdf(ds, tmp_path / "a.nc")
    assert not list(tmp_path.iterdir())


def test_valid_tests_load_the_variables_asked_for(tmp_path):
    for i, valid in enumerate([1, 0, 1]):
        write_netcdf(every_kind().assign_attrs(test_id=f"T{i}", valid=valid), tmp_path / f"T{i}.nc")
    tests = list(valid_tests(sorted(tmp_path.glob("*.nc")), variables=("theta",)))
    assert [ds.attrs["test_id"] for ds in tests] == ["T0", "T2"]
    assert all(list(ds.variables) == ["theta", "time"] for ds in tests)
