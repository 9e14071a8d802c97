"""The one helper for stored variables' attributes (workbench._attributes)."""

import numpy as np
import pytest
import xarray as xr

from workbench._attributes import flag_meaning, flag_names, flags, named, variable


def test_a_variable_carries_its_name_and_units_first():
    a = variable("clearance", "m", comment="radial")
    assert list(a) == ["long_name", "units", "comment"]
    assert a["units"] == "m"
    assert variable("ratio")["units"] == "1"


@pytest.mark.parametrize("units", ["", None, 3])
def test_a_variable_without_units_is_refused_by_name(units):
    with pytest.raises(ValueError, match="units of 'clearance'"):
        variable("clearance", units)


def test_flags_are_cf_pairs_from_a_sequence_or_a_mapping():
    a = flags("outcome", ["ok", "failed upper bound"])
    assert a["flag_values"].dtype == np.int8
    assert a["flag_values"].tolist() == [0, 1]
    assert a["flag_meanings"] == "ok failed_upper_bound"
    b = flags("status", {0: "ok", 3: "stalled"}, dtype=np.int16)
    assert b["flag_values"].tolist() == [0, 3] and b["flag_values"].dtype == np.int16
    da = xr.DataArray(np.int8(3), name="status", attrs=b)
    assert flag_names(da) == ["ok", "stalled"]
    assert flag_meaning(da, 3) == "stalled"
    with pytest.raises(KeyError, match="no flag 2"):
        flag_meaning(da, 2)


def test_repeated_flag_meanings_are_refused():
    with pytest.raises(ValueError, match="distinct"):
        flags("outcome", ["ok", "ok"])


def test_a_variable_without_units_carries_only_its_name():
    assert named("failure message", comment="empty when ok") == {
        "long_name": "failure message",
        "comment": "empty when ok",
    }
