"""Analysis that says when there is nothing to analyse (issue 23 item 6) and one answer with its
flag in the API and the CLI (issue 26 item 3).

The issue's cases: a constant series was told to "record a longer series"; a near-constant one
failed with "scale_min=0.0 and scale_max=0.0" (3 001 samples) or ran for more than 300 s
(30 001); white noise of amplitude 1e-9 read "Wolf LLE 3.73 1/s" on the command line with no
warning. Each case here must give its verdict at once: a per-test timeout (a hang guard far
above the seconds they take, not a speed figure) fails one that regresses to minutes.
"""

import numpy as np
import pytest
import xarray as xr

import workbench
from workbench.analysis import (
    embedding_cao,
    embedding_fnn,
    no_dynamics,
    rosenstein_lle,
    surrogate_test,
    wolf_lle,
)
from workbench.cli import main

N = 30001  # the long case


def _spike(n):
    x = np.ones(n)
    x[n // 2] += 1e-12
    return x


DEGENERATE = {
    "constant": (lambda n: np.full(n, 1e-4), "is constant"),
    "rounding": (
        lambda n: 1.0 + 1e-16 * np.random.default_rng(0).standard_normal(n),
        "rounding level",
    ),
    "spike": (_spike, "sits at 1 at 30000 of its 30001 samples"),
    "step": (lambda n: np.r_[np.zeros(n // 2), np.ones(n - n // 2)], "sits at 1"),
    "quantised": (
        lambda n: 1e-3 * np.round(np.random.default_rng(0).standard_normal(n)),
        "distinct values",
    ),
}


@pytest.mark.timeout(120)
@pytest.mark.parametrize("case", sorted(DEGENERATE))
def test_a_series_without_dynamics_gets_its_verdict_at_once(case):
    make, words = DEGENERATE[case]
    x = make(N)
    assert words in no_dynamics(x)
    for estimate in (
        lambda: wolf_lle(x, dt=0.01),
        lambda: embedding_fnn(x, delay=1),
        lambda: embedding_cao(x, delay=1),
        lambda: rosenstein_lle(x, dt=0.01),
    ):
        with pytest.raises(ValueError, match=words):
            estimate()  # was > 300 s (spike, 30 001 samples)


def test_a_moving_series_has_dynamics():
    t = np.arange(3000)
    assert no_dynamics(np.sin(0.05 * t)) is None
    assert no_dynamics(np.random.default_rng(0).standard_normal(3000)) is None
    assert no_dynamics(np.arange(5.0)) is None  # too short to judge: the estimators' length rules
    da = xr.DataArray(np.zeros(200), dims="time", name="contact_force", attrs={"units": "N"})
    assert no_dynamics(da) == (
        "contact_force is constant (0 N at all 200 samples): no dynamics to analyse"
    )


def henon(n: int) -> np.ndarray:
    x = np.empty(n + 100)
    a, b = 0.1, 0.0
    for i in range(n + 100):
        a, b = 1 - 1.4 * a * a + b, 0.3 * a
        x[i] = a
    return x[100:]


def test_surrogate_test_tells_determinism_from_linear_noise():
    """Henon is predicted far better than its IAAFT surrogates; white noise and an AR(1)
    process (linear correlated noise) are not."""
    r = surrogate_test(henon(2000), dim=2, delay=1, horizon=1)
    assert int(r.deterministic) == 1 and float(r.p_value) == pytest.approx(0.05)
    assert float(r.error) < 0.1 < float(r.surrogate_error.min())
    rng = np.random.default_rng(3)
    ar = np.zeros(4000)
    for i in range(1, ar.size):
        ar[i] = 0.95 * ar[i - 1] + rng.standard_normal()
    for series in (rng.standard_normal(3000), ar):
        r = surrogate_test(series, dim=3, delay=1, horizon=1)
        assert int(r.stochastic) == 1 and float(r.p_value) > 0.05
    with pytest.raises(ValueError, match="surrogates=5"):
        surrogate_test(ar, dim=2, delay=1, surrogates=5)


@pytest.mark.timeout(120)
def test_tiny_white_noise_is_flagged_in_seconds():
    """The issue's case: white noise of amplitude 1e-9 sampled at 0.01 s. A positive exponent
    comes out (any estimator finds one in noise), flagged by Cao's E2 and by the surrogates."""
    x = 1e-9 * np.random.default_rng(2).standard_normal(3001)
    r = wolf_lle(x, dt=0.01)
    assert float(r.lle) > 0 and not bool(r.reliable)
    assert int(r.stochastic) == 1 and int(r.surrogate_stochastic) == 1
    reasons = r.reliable.attrs["reasons"].splitlines()
    assert any("Cao's E2" in line for line in reasons)
    assert any("IAAFT surrogates" in line for line in reasons)
    assert r.reliable.attrs["message"] == "; ".join(reasons)


def test_chaos_passes_the_surrogate_test():
    r = wolf_lle(henon(3000))
    assert bool(r.reliable) and int(r.surrogate_stochastic) == 0
    assert r.surrogate_error.sizes["surrogate"] == 19
    off = wolf_lle(henon(3000), surrogates=0)
    assert int(off.surrogate_stochastic) == -1 and float(off.lle) == float(r.lle)
    with pytest.raises(ValueError, match="surrogates=3"):
        wolf_lle(henon(3000), surrogates=3)


def _run_file(tmp_path, values, dt=0.01, name="x"):
    """A minimal stored run with one series over time (what 'workbench analyse' reads)."""
    time_ = dt * np.arange(values.size)
    ds = xr.Dataset(
        {name: ("time", values, {"units": "m", "long_name": name})},
        coords={"time": ("time", time_, {"units": "s", "long_name": "time"})},
        attrs={"scene": ""},
    )
    return str(workbench.save_run(ds, tmp_path / "series.nc"))


def test_cli_prints_the_flag_of_noise(tmp_path, capsys):
    path = _run_file(tmp_path, 1e-9 * np.random.default_rng(2).standard_normal(3001))
    assert main(["analyse", path, "--var", "x", "-o", str(tmp_path / "figs")]) == 0
    out = capsys.readouterr().out
    assert "reliable: NO, flagged:" in out
    assert "Cao's E2" in out and "surrogate test: not told from linear noise" in out
    assert "Rosenstein LLE (nolds" in out


@pytest.mark.timeout(120)
def test_cli_says_a_constant_series_has_no_dynamics(tmp_path, capsys):
    path = _run_file(tmp_path, np.full(N, 2.5e-4))
    assert main(["analyse", path, "--var", "x", "-o", str(tmp_path / "figs")]) == 0
    out = capsys.readouterr().out
    assert out.strip() == "x is constant (0.00025 m at all 30001 samples): no dynamics to analyse"
    assert not (tmp_path / "figs").exists()


def test_cli_makes_the_apis_choices(tmp_path, capsys):
    """The issue's disagreement: the CLI forced the FNN dimension and read 13.91 1/s where the
    API read 6.04 on the same series. Now both read one number, with one flag."""
    x = henon(3000)  # a map given a time step (0.5 s): the API takes it for a map, and says so
    path = _run_file(tmp_path, x, dt=0.5)
    api = wolf_lle(workbench.open_run(path).x)
    assert not bool(api.reliable)
    cli = ["analyse", path, "--var", "x", "-o", str(tmp_path), "--overwrite"]
    assert main(cli) == 0
    out = capsys.readouterr().out
    assert f"Wolf LLE: {float(api.lle):.4g} 1/s" in out
    assert f"embedding dimension: {int(api.dim)} (false nearest neighbours" in out
    assert "series: map (detected" in out and "reliable: NO, flagged:" in out
    assert "does not look like a sampled flow" in out and "--kind map" in out
    # the overrides are said to be given, and change what they should
    assert main(cli + ["--kind", "map"]) == 0
    out = capsys.readouterr().out
    assert "series: map (given" in out and "reliable: yes" in out
    assert "surrogate test: deterministic" in out
    assert main(cli + ["--dim", "4"]) == 0
    out = capsys.readouterr().out
    assert "embedding dimension: 4 (given" in out
    assert f"Wolf LLE: {float(wolf_lle(x, dt=0.5, dim=4).lle):.4g} 1/s" in out
