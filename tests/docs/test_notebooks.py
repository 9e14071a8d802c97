"""The notebooks (issue 26 item 2): each runs top to bottom on the committed archives in data/
(nbclient); the outputs committed with it (which the docs site shows) are the ones it gives now
(``make notebooks`` rewrites them); and its key numbers are the API's, computed here
independently: notebook 02's Wolf exponent with its reliability flag and reasons, notebook 01's
energy residual and peaks, notebook 03's failed points, notebook 05's strobe periods and
chaos indicators of the declared four-bar and what its text says of them."""

import re
from pathlib import Path

import nbformat
import numpy as np
import pytest
from nbclient import NotebookClient

import workbench
from workbench import analysis

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


def test_there_are_notebooks():
    assert len(NOTEBOOKS) >= 3


def _text(nb) -> list[list[str]]:
    """The text outputs of each code cell (streams and text/plain results; not images). The
    kernel sends printed text in chunks as its buffer flushes, which depends on timing: one
    cell's consecutive stdout chunks are joined into one text."""
    out = []
    for cell in nb.cells:
        if cell.cell_type != "code":
            continue
        texts, streaming = [], False
        for o in cell.get("outputs", []):
            if o.get("output_type") == "stream" and o.get("name") == "stdout":
                if streaming:
                    texts[-1] += o["text"]
                else:
                    texts.append(o["text"])
                streaming = True
                continue
            streaming = False
            if "data" in o and "text/plain" in o["data"] and "image/png" not in o["data"]:
                texts.append(o["data"]["text/plain"])
        out.append([t.rstrip() for t in texts])
    return out


@pytest.fixture(scope="module")
def executed():
    """Each notebook executed now: (committed, fresh)."""
    results = {}
    for path in NOTEBOOKS:
        committed = nbformat.read(path, as_version=4)
        fresh = nbformat.read(path, as_version=4)
        NotebookClient(
            fresh,
            timeout=600,
            kernel_name="python3",
            resources={"metadata": {"path": str(path.parent)}},
        ).execute()
        results[path.stem] = committed, fresh
    return results


def _stdout(nb) -> str:
    return "\n".join(t for cell in _text(nb) for t in cell)


@pytest.mark.slow
@pytest.mark.parametrize("stem", [p.stem for p in NOTEBOOKS])
def test_notebook_runs_and_its_committed_outputs_are_current(stem, executed):
    committed, fresh = executed[stem]
    errors = [
        o
        for cell in fresh.cells
        if cell.cell_type == "code"
        for o in cell.get("outputs", [])
        if o.get("output_type") == "error"
    ]
    assert not errors
    assert all(c.get("outputs") for c in committed.cells if c.cell_type == "code" and c.source)
    assert _text(committed) == _text(fresh), "stale outputs: run 'make notebooks'"


@pytest.mark.slow
def test_notebook_02_quotes_the_apis_exponent_and_flag(executed):
    out = _stdout(executed["02_chaos_identification"][1])
    ds = workbench.open_run(ROOT / "data" / "chaos_run.nc")
    wolf = analysis.wolf_lle(ds.clearance_x.sel(joint="A"), period=ds.attrs["forcing_period"])
    assert f"Wolf LLE {float(wolf.lle):.4g} 1/s" in out
    assert f"reliable: {bool(wolf.reliable)}" in out
    for reason in wolf.reliable.attrs["reasons"].splitlines():
        assert f" - {reason}" in out
    # the text after the flag says the value is not the mechanism's exponent: it must be flagged
    assert not bool(wolf.reliable)
    assert "does not look like a sampled flow" in wolf.reliable.attrs["reasons"]


@pytest.mark.slow
def test_notebook_01_and_03_quote_the_archives(executed):
    out = _stdout(executed["01_explore_a_stored_run"][1])
    ds = workbench.open_run(ROOT / "data" / "ninebar_default.nc")
    for name in ("slider_velocity", "slider_acceleration", "contact_force"):
        v = ds[name].values.ravel()
        assert re.search(rf"{name}\s+{v[np.nanargmax(abs(v))]:9.4g}", out)
    assert f"archive format {workbench.FORMAT_VERSION}" in out
    out = _stdout(executed["03_bifurcation_campaign"][1])
    camp = workbench.open_run(ROOT / "data" / "bifurcation_speed.nc")
    assert f"failed points: {int((camp.status != 0).sum())} of {camp.status.size}" in out


def test_notebook_text_quotes_no_number_of_its_own():
    """Markdown cells cite sections, figures, equations, years and bodies (crank 4), never a
    result: the numbers a reader sees are outputs of the code."""
    allowed = re.compile(
        r"(Sec\.|Figs?\.|Eq\.|crank)\s?[\d.-]+|\b(19|20)\d\d\b|0-1 test"  # citations, names
    )
    for path in NOTEBOOKS:
        for cell in nbformat.read(path, as_version=4).cells:
            if cell.cell_type != "markdown":
                continue
            text = re.sub(r"```.*?```", "", cell.source, flags=re.S)  # code shown, not run
            text = allowed.sub("", text)
            assert not re.findall(r"\b\d+(?:\.\d+)?\b", text), (path.name, text[:200])


@pytest.mark.slow
def test_notebook_04_quotes_the_chaos_maps(executed):
    out = _stdout(executed["04_chaos_maps"][1])
    maps = workbench.open_run(ROOT / "data" / "omega_clearance_map.nc")
    period = maps.strobe_period
    assert f"periodic points: {int((period > 0).sum())} of {period.size}" in out
    unmet = maps.lle_unmet.values.astype(int)
    meanings = maps.lle_unmet.attrs["flag_meanings"].split()
    for name, mask in zip(meanings, maps.lle_unmet.attrs["flag_masks"], strict=True):
        n = int(((unmet & mask) != 0).sum())
        assert (f"{name}: {n} points" in out) == (n > 0), name
    other = workbench.open_run(ROOT / "data" / "clearance_friction_map.nc")
    theirs = other.sel(friction_coefficient=float(maps.friction_coefficient), method="nearest")
    mine = maps.sel(omega=float(other.omega), method="nearest").sel(
        clearance=theirs.clearance.values, method="nearest"
    )
    diff = np.abs(mine.lle.values - theirs.lle.values)
    errors = np.hypot(mine.lle_stderr.values, theirs.lle_stderr.values)
    agree = (diff <= 0.1 * np.abs(theirs.lle.values)) | (diff <= 2 * errors)
    assert f"{int(agree.sum())} of {agree.size}" in out and agree.all()


def _fourbar_periods(sweep) -> dict[str, np.ndarray]:
    """The strobe period of every point of the four-bar's continued sweep, per direction."""
    from workbench.continuation import strobe_period

    out = {}
    for d in ("up", "down"):
        p = sweep.sel(direction=d, joint="B")
        xy = [p[v].transpose("omega", "record").values for v in ("clearance_x", "clearance_y")]
        samples = np.stack(xy, axis=-1)
        out[d] = np.array([strobe_period(row) for row in samples])
    return out


@pytest.mark.slow
def test_notebook_05_quotes_the_fourbar_archives(executed):
    """Notebook 05's printed periods and indicators are the archives', and what its text says
    in words holds: period one, then two, then one going up, no period beyond; the motion
    without a period one step lower coming down (two attractors at that speed); the journal on
    the wall at period one; at the map's highest speed chaos at the two larger clearances; at
    its middle speed a point without a period whose exponent is negative; the map's point at
    the largest clearance and the middle speed is the up branch's motion of period one."""
    out = _stdout(executed["05_your_own_mechanism"][1])
    sweep = workbench.open_run(ROOT / "data" / "fourbar_sweep.nc")
    period = _fourbar_periods(sweep)
    w = sweep.omega.values
    assert f"failed points: {int((sweep.status != 0).sum())} of {sweep.status.size}" in out
    for d, row in period.items():
        assert f"{d:>13}: " + " ".join(f"{k:3d}" for k in row) in out
    up, down = period["up"], period["down"]
    k = int(np.argmax(up != 1))  # the first speed going up without period one
    assert k > 0 and up[k] == 2 and up[k + 1] == 1 and (up[k + 2 :] == 0).all()
    assert (up[:k] == 1).all() and (down[: k + 1] == up[: k + 1]).all()
    assert (np.flatnonzero(up != down) == [k + 1]).all() and down[k + 1] == 0
    assert (down[k + 1 :] == 0).all()
    assert f"the directions differ at: {w[k + 1]:.0f} rad/s" in out
    half = sweep.record >= sweep.sizes["record"] // 2
    ecc = np.hypot(sweep.clearance_x, sweep.clearance_y).sel(joint="B").where(half)
    ecc = ecc / float(sweep.clearance_B)
    for d, row in period.items():
        e = ecc.sel(direction=d)
        at_one = e.sel(omega=w[row == 1])
        assert 1.0 <= float(at_one.min()) and float(at_one.max()) < 1.01  # "a hair beyond c"
        first = w[np.argmax(row == 0)]
        assert float(e.sel(omega=first).min()) > 0.9  # "at first ... close to the wall"
        assert float(e.sel(omega=w[-1]).min()) < 0.5  # "they spread over the bearing"
    maps = workbench.open_run(ROOT / "data" / "fourbar_chaos_map.nc")
    assert f"failed points: {int((maps.status != 0).sum())} of {maps.status.size}" in out
    method = maps.lle_method.attrs["flag_meanings"].split()
    for w_ in maps.omega.values:
        for c_ in maps.clearance_B.values:
            p = maps.sel(omega=w_, clearance_B=c_)
            lle = rf"{float(p.lle):.1f} \+- {float(p.lle_stderr):4.1f}"
            assert re.search(
                rf"{w_:13.0f} {c_ * 1e3:6.1f} {int(p.strobe_period):6d} {float(p.zero_one_K):5.2f}"
                rf"\s+{lle}  {method[int(p.lle_method)]}",
                out,
            ), (w_, c_)
    table = maps.transpose("clearance_B", "omega", ...)
    periodic = table.strobe_period > 0
    assert (table.lle.where(periodic) < 0).sum() == periodic.sum()  # negative where periodic
    assert float(table.zero_one_K.where(periodic).max()) < 0.6  # "well below one"
    top = table.isel(omega=-1, clearance_B=slice(1, None))  # the highest speed, larger c
    assert (top.strobe_period == 0).all() and (top.zero_one_K > 0.9).all()
    assert (top.lle > 3 * top.lle_stderr).all() and (top.lle_converged > 0).all()
    assert int((table.isel(clearance_B=0).strobe_period == 0).sum()) == 0
    middle = table.isel(omega=1, clearance_B=1)
    assert int(middle.strobe_period) == 0 and float(middle.zero_one_K) > 0.9
    assert float(middle.lle) < 0 and int(middle.lle_converged) > 0
    assert int((table.strobe_period == 0).sum()) == 3  # the three points named above
    largest = table.isel(omega=1, clearance_B=-1)
    assert int(largest.strobe_period) == 1 and float(largest.clearance_B) == float(
        sweep.clearance_B
    )
    j = int(np.flatnonzero(w == float(largest.omega))[0])
    assert j == k + 1 and up[j] == 1 and down[j] == 0  # the two motions the sweep found
    assert "chaotic (no period, exponent converged and positive beyond 3 standard errors): 2" in out


def test_the_readme_counts_the_notebooks():
    words = {3: "three", 4: "four", 5: "five", 6: "six"}
    readme = (ROOT / "README.md").read_text()
    assert f"`notebooks/` ({words[len(NOTEBOOKS)]} notebooks" in readme
