"""Which points a campaign's blocks hold: dealt by estimated cost, recorded in the manifest, and
stores of the former contiguous layout still resumed."""

import json
import math
import warnings

import numpy as np
import pytest

import workbench
from workbench.campaign import CampaignError, expand_sweep, store_paths
from workbench.campaign._schedule import block_order, partition, simulated_span

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
    cost = [sum(simulated_span(scene, grid, f) for f in b) for b in blocks]
    contiguous = [sum(simulated_span(scene, grid, f) for f in r) for r in grid.blocks(5)]
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
