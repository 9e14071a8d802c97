"""The notebooks (issue 26 item 2): each runs top to bottom on the committed archives in data/
(nbclient); the outputs committed with it (which the docs site shows) are the ones it gives now
(``make notebooks`` rewrites them); and its key numbers are the API's, computed here
independently: notebook 02's Wolf exponent with its reliability flag and reasons, notebook 01's
energy residual and peaks, notebook 03's failed points."""

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
    assert "shared points identical: True" in out


def test_the_readme_counts_the_notebooks():
    words = {3: "three", 4: "four", 5: "five", 6: "six"}
    readme = (ROOT / "README.md").read_text()
    assert f"`notebooks/` ({words[len(NOTEBOOKS)]} notebooks" in readme
