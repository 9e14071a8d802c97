"""Which points a campaign's blocks hold: dealt by estimated cost, recorded in the manifest, and
stores of the former contiguous layout still resumed; the plan of a huge grid from arrays."""

import json
import math
import warnings

import numpy as np
import pytest

import workbench
from workbench.campaign import CampaignError, expand_sweep, store_paths
from workbench.campaign._grid import check_archive_memory, grid_periods
from workbench.campaign._schedule import block_order, deal, partition, simulated_spans
from workbench.models import get_model

BASE = {
    "model": {"name": "duffing"},
    "parameters": {"delta": 0.3, "alpha": -1.0, "beta": 1.0, "gamma": 0.3},
    "run": {"cycles": 6, "transient_cycles": 2},
    "record": {"samples_per_period": 1},
}


def test_blocks_are_dealt_so_that_they_cost_about_the_same():
    """A sweep over the forcing frequency: the simulated time of a point falls as 1/omega, so
    contiguous blocks would differ 10x in cost; dealt by tiers, every block holds one point of
    each tier of cost."""
    omegas = list(np.linspace(0.3, 3.0, 23))
    scene = workbench.load_scene({**BASE, "sweep": {"omega": omegas}})
    grid = expand_sweep(scene)
    blocks = partition(scene, grid, 5)
    assert len(blocks) == math.ceil(23 / 5) == 5
    assert sorted(f for b in blocks for f in b) == list(range(23))
    assert all(len(b) <= 5 for b in blocks) and all(list(b) == sorted(b) for b in blocks)
    assert sorted(b[0] for b in blocks) == [0, 1, 2, 3, 4]  # one of the 5 costliest each
    span = simulated_spans(scene, grid)
    cost = [sum(span[f] for f in b) for b in blocks]
    contiguous = [sum(span[f] for f in r) for r in grid.blocks(5)]
    assert max(cost) / min(cost) < 1.35 and max(contiguous) / min(contiguous) > 5
    assert block_order(scene, grid, blocks) == sorted(range(5), key=lambda i: -cost[i])


def test_equal_costs_spread_each_block_over_the_grid():
    scene = workbench.load_scene({**BASE, "sweep": {"gamma": list(np.linspace(0.2, 0.5, 8))}})
    blocks = partition(scene, expand_sweep(scene), 3)
    assert blocks == [(0, 3, 6), (1, 4, 7), (2, 5)]  # every third point


def test_the_manifest_records_the_blocks_and_a_contiguous_store_resumes(tmp_path):
    scene = workbench.load_scene({**BASE, "sweep": {"omega": [0.5, 1.0, 1.5, 2.0, 2.5]}})
    store = tmp_path / "c.nc"
    whole = workbench.run_campaign(scene, store, workers=1, chunk=2)
    manifest = json.loads(store_paths(store)["manifest"].read_text())
    assert manifest["format"] == "workbench-campaign 3"
    assert manifest["block_points"] == [[0], [1, 4], [2, 3]]  # omega falls: cost falls
    for i, points in enumerate(manifest["block_points"]):
        block = workbench.open_run(store_paths(store)["blocks"] / f"block-{i:05d}.nc")
        assert list(block.point.values) == points

    # a store written before blocks were dealt (format 2): contiguous blocks of chunk points,
    # two of three committed; the resume computes the third as it was laid out
    old = tmp_path / "old.nc"
    workbench.run_campaign(scene, old, workers=1, chunk=2, restart=True)
    paths = store_paths(old)
    paths["archive"].unlink()
    m = json.loads(paths["manifest"].read_text())
    contiguous = [list(r) for r in expand_sweep(scene).blocks(2)]
    m.pop("block_points")
    m["format"] = "workbench-campaign 2"
    m["checksums"], m["code_digests"] = {}, {}
    paths["manifest"].write_text(json.dumps(m))
    for p in paths["blocks"].glob("block-*.nc"):
        p.unlink()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        resumed = workbench.run_campaign(scene, old, workers=1)
    for i, points in enumerate(contiguous):
        block = workbench.open_run(paths["blocks"] / f"block-{i:05d}.nc")
        assert list(block.point.values) == points
    np.testing.assert_array_equal(resumed.x.values, whole.x.values)

    m = json.loads(paths["manifest"].read_text())
    m.update(format="workbench-campaign 3", block_points=[[0, 1], [1, 2, 3, 4]])
    paths["archive"].unlink()
    paths["manifest"].write_text(json.dumps(m))
    with pytest.raises(CampaignError, match="do not hold each of the 5 points"):
        workbench.run_campaign(scene, old, workers=1)


def _dealt_tier_by_tier(cost: list[float], count: int) -> list[int]:
    """The deal as first written, point by point in Python (the reference of :func:`deal`):
    the block of each point."""
    ranked = sorted(range(len(cost)), key=lambda f: (-cost[f], f))
    block, load = [0] * len(cost), [0.0] * count
    for start in range(0, len(cost), count):
        seats = sorted(range(count), key=lambda b: (load[b], b))
        for flat, b in zip(ranked[start : start + count], seats, strict=False):
            block[flat] = b
            load[b] += cost[flat]
    return block


def test_the_deal_on_arrays_is_the_deal_point_by_point():
    """The array deal gives every point the block the point-by-point deal gives it: runs of
    equal cost (one cumulative sum of the blocks' costs), tiers that mix costs, and costs a
    few ulps apart, whose sums become equal as they grow (the order of two blocks then falls to
    their index)."""
    rng = np.random.default_rng(0)
    pools = (
        [0.1, 0.2, 0.3, 1 / 3, 2 / 3, 1e-3, 7.0, 1e16, 1.0],
        [1.0 - i * 1.1e-16 for i in range(8)],  # sums of these tie after a few tiers
    )
    for case in range(400):
        n = int(rng.integers(1, 300))
        count = int(rng.integers(1, (n if case % 2 else min(n, 12)) + 1))
        pool = pools[case % 4 == 0]
        values = rng.choice(pool, int(rng.integers(1, 6)), replace=False)
        cost = rng.random(n) if case % 7 == 0 else rng.choice(values, n)
        assert deal(cost, count).tolist() == _dealt_tier_by_tier(cost.tolist(), count), case


def _counting_period(monkeypatch, period):
    """Make the Duffing model's forcing period ``period(params)``; returns the list of the
    parameters of every call."""
    calls = []
    model = type(get_model("duffing"))

    def counted(self, params):
        calls.append(params)
        return period(params)

    monkeypatch.setattr(model, "forcing_period", counted)
    return calls


def test_a_huge_grid_is_planned_from_arrays(monkeypatch):
    """The finding of issue 37: a grid of 10^7 points printed nothing for minutes while the
    memory estimate and the planner called the model once per point. Now the forcing period is
    evaluated once per value of what it reads, and the rest is arrays."""
    calls = _counting_period(monkeypatch, lambda p: 2 * np.pi / p["omega"])
    huge = workbench.load_scene(
        {
            **BASE,
            "sweep": {
                "gamma": {"start": 0.2, "stop": 0.5, "num": 10000},
                "delta": {"start": 0.1, "stop": 0.4, "num": 1000},
            },
        }
    )
    grid = expand_sweep(huge)
    assert grid.size == 10**7
    calls.clear()  # (loading the scene asked for its period)
    periods = grid_periods(huge, grid)
    assert periods.shape == (1, 1) and periods[0, 0] == 2 * np.pi / 1.2  # the scene's omega
    assert len(calls) == 2  # the scene's parameters, then the one combination read
    # 10^7 points x (6 cycles x 1 sample + 1) records x (x, v, time) x 8 bytes
    assert check_archive_memory(huge, grid, "1 TiB") == 8.0 * 10**7 * 7 * 3
    first, last = grid.rows([0, grid.size - 1])
    assert first == (0.2, 0.1) and last == (0.5, 0.4)
    assert grid.rows([123456]) == (tuple(grid.point(123456).values()),)

    omega = workbench.load_scene(  # a sweep over omega: one evaluation per value of omega
        {
            **BASE,
            "record": {"dt": 0.5},
            "sweep": {
                "omega": {"start": 0.5, "stop": 3.0, "num": 1000},
                "gamma": {"start": 0.2, "stop": 0.5, "num": 1000},
            },
        }
    )
    grid = expand_sweep(omega)
    calls.clear()
    periods = grid_periods(omega, grid)
    # the scene's parameters; a first call that reads omega; then each value of omega
    assert periods.shape == (1000, 1) and len(calls) == 2 + 1000
    np.testing.assert_array_equal(periods[:, 0], 2 * np.pi / np.array(grid.values[0]))
    # the most records: omega 0.5, a period of 4 pi s sampled every 0.5 s (25 per period)
    assert check_archive_memory(omega, grid, "1 TiB") == 8.0 * 10**6 * (6 * 25 + 1) * 3
    calls.clear()
    blocks = partition(omega, grid, 125000)  # 8 blocks of 125000 points
    assert len(calls) == 2 + 1000  # not one per point
    assert sorted(len(b) for b in blocks) == [125000] * 8
    flat = np.concatenate(blocks)
    assert (np.bincount(flat, minlength=grid.size) == 1).all()
    span = simulated_spans(omega, grid)
    cost = [span[list(b)].sum() for b in blocks]
    assert max(cost) / min(cost) < 1 + 1e-3  # dealt by tiers: the blocks cost the same


def test_the_periods_are_the_model_s_at_each_point(monkeypatch):
    """What the forcing period reads is found as it runs: a key read only at some points (here
    gamma when omega > 1), or all of them when it iterates over the parameters or needs a dict;
    the periods are then those of a call at each point."""
    scene = workbench.load_scene(
        {
            **BASE,
            "sweep": {
                "gamma": [0.2, 0.3, 0.4],
                "omega": [0.5, 1.5, 2.5],
                "delta": [0.1, 0.2],
                "realisation": [0, 1],
            },
        }
    )
    grid = expand_sweep(scene)
    periods = {
        "conditional": lambda p: 2 * np.pi / p["omega"] * (1 + p["gamma"] if p["omega"] > 1 else 1),
        "iterating": lambda p: 2 * np.pi / p["omega"] + 1e-3 * sum(dict(p).values()),
        "a dict": lambda p: 2 * np.pi / p.copy()["delta"],
    }
    for name, period in periods.items():
        calls = _counting_period(monkeypatch, period)
        base = scene.resolved_parameters
        every = [period({**base, **grid.point(f)}) for f in range(grid.size)]
        got = np.broadcast_to(grid_periods(scene, grid), grid.shape).ravel()
        assert got.tolist() == every, name
        assert len(calls) < 2 * grid.size + 2, name  # at most twice per point


def test_a_point_whose_forcing_period_fails_is_refused_not_costed(monkeypatch, tmp_path):
    """Issue 41: the cost estimate turned any error of the forcing period into a cost of 0.
    Now the point is named in one line, before anything is planned or written."""

    def period(p):
        if p["omega"] == 2.0:
            raise ZeroDivisionError("float division by zero")
        return 2 * np.pi / p["omega"]

    _counting_period(monkeypatch, period)
    scene = workbench.load_scene({**BASE, "sweep": {"omega": [1.0, 2.0, 3.0], "gamma": [0.3]}})
    with pytest.raises(CampaignError) as caught:
        simulated_spans(scene, expand_sweep(scene))
    message = str(caught.value)
    assert "\n" not in message and "at omega=2 (any other swept values)" in message
    assert "ZeroDivisionError: float division by zero" in message
    _counting_period(monkeypatch, lambda p: -1.0 if p["omega"] == 3.0 else 2 * np.pi)
    bad = r"at omega=3 .*: model 'duffing' gives the forcing period -1\.0, not a finite positive"
    with pytest.raises(CampaignError, match=bad):
        workbench.run_campaign(scene, tmp_path / "c.nc", workers=1)
    assert not store_paths(tmp_path / "c.nc")["blocks"].exists()
