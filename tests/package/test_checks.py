"""Argument checks written once (workbench._checks)."""

from pathlib import Path

import numpy as np
import pytest
from _scenes import DUFFING_SWEEP

from workbench._checks import positive_int


@pytest.mark.parametrize("value", [1, 7, np.int64(3)])
def test_a_positive_integer_passes_as_an_int(value):
    out = positive_int("workers", value)
    assert out == int(value) and type(out) is int


@pytest.mark.parametrize("value", [0, -2, 1.0, 2.5, True, "3", None])
def test_anything_else_is_refused_naming_the_argument_and_the_value(value):
    with pytest.raises(ValueError, match=rf"^workers must be a positive integer, got {value!r}$"):
        positive_int("workers", value)


def test_none_passes_only_where_allowed():
    assert positive_int("chunk", None, allow_none=True) is None
    with pytest.raises(ValueError, match="chunk must be a positive integer or None, got 0"):
        positive_int("chunk", 0, allow_none=True)


def test_the_public_functions_use_it(tmp_path):
    """floquet's periods and run_campaign's workers are refused before any work."""
    import workbench
    from workbench.analysis import floquet

    duffing = Path(__file__).resolve().parents[2] / "studies" / "duffing.toml"
    with pytest.raises(ValueError, match="^periods must be a positive integer, got 0$"):
        floquet(duffing, periods=0)
    with pytest.raises(ValueError, match="^workers must be a positive integer or None, got True$"):
        workbench.run_campaign(DUFFING_SWEEP, tmp_path / "x.nc", workers=True)
