"""The benchmarks' records (issue 40 item 11): one JSON file per run in benchmarks/records/, with
its command, commit, machine, load, CPU and wall time, named figures and printed output
(benchmarks/_results.py), and benchmarks/RESULTS.md, the page generated from them and from the
measurements made by hand (benchmarks/NOTES.md)."""

import datetime
import json
import re
from pathlib import Path

import numpy as np
import pytest
from _records import NOTES, ROOT, results

FIELDS = {
    "benchmark": str,
    "command": str,
    "outcome": str,
    "started": str,
    "commit": str,
    "machine": str,
    "load_before": (list, type(None)),
    "load_after": (list, type(None)),
    "cpu_seconds": (int, float),
    "wall_seconds": (int, float),
    "figures": dict,
    "output": str,
}


def test_the_results_page_is_generated_from_the_records():
    """RESULTS.md is what ``python benchmarks/_results.py`` writes from the records and NOTES.md
    (after a merge that brought records, or an edit of NOTES.md, run it again)."""
    page = (ROOT / "benchmarks" / "RESULTS.md").read_text()
    assert page == results.render(results.load_records(), NOTES.read_text())
    for title in re.findall(r"^#+ (.*)$", NOTES.read_text(), re.M)[1:]:  # what the docs cite
        assert f"# {title}\n" in page


def test_every_record_has_its_fields_and_is_named_by_its_start_and_commit():
    found = results.load_records()
    assert len(found) >= 44  # the runs logged before the records were JSON, converted
    for r in found:
        path = ROOT / r.pop("file")
        assert set(FIELDS) <= r.keys() <= set(FIELDS) | {"note"}, path
        for key, kind in FIELDS.items():
            assert isinstance(r[key], kind), (path, key)
        script = ROOT / "benchmarks" / r["benchmark"]
        assert script.is_file() or r["benchmark"] in results.RETIRED, path
        assert r["command"].startswith(f"python benchmarks/{r['benchmark']}"), path
        assert re.fullmatch(r"[0-9a-f]{7,40}(-dirty)?", r["commit"]), path
        started = datetime.datetime.strptime(r["started"], "%Y-%m-%dT%H:%M:%SZ")
        stamp = f"{started:%Y%m%dT%H%M%SZ}-{r['commit']}"
        assert re.fullmatch(rf"{stamp}(-\d+)?\.json", path.name), path
        assert path.parent.name == r["benchmark"].removesuffix(".py"), path
        assert r["outcome"] == "completed" or r["outcome"].startswith("failed: "), path
        for load in (r["load_before"], r["load_after"]):
            assert load is None or (len(load) == 3 and all(v >= 0 for v in load)), path


@pytest.fixture
def scratch(tmp_path, monkeypatch):
    """The records, NOTES.md and RESULTS.md of benchmarks/_results.py moved into tmp_path."""
    notes = tmp_path / "NOTES.md"
    notes.write_text("# Notes\n\n## Measured by hand\n\nA figure.\n")
    for name, value in [
        ("RECORDS", tmp_path / "records"),
        ("NOTES", notes),
        ("PAGE", tmp_path / "RESULTS.md"),
    ]:
        monkeypatch.setattr(results, name, value)
    monkeypatch.delenv("WORKBENCH_RESULTS", raising=False)
    monkeypatch.setattr("sys.argv", ["benchmarks/fake.py", "--cycles", "2"])
    return tmp_path


def test_a_run_is_one_record_with_its_figures_and_the_page_follows(scratch, capsys):
    with results.recording("benchmarks/fake.py"):
        print("a table")
        results.record({"window": {"rtol": np.float64(1e-6)}, "steps": np.arange(3)})
        results.record({"window": {"cycles": 2}, "sum_check": float("nan")})
    assert "a table" in capsys.readouterr().out  # still printed
    (path,) = (scratch / "records" / "fake").glob("*.json")
    r = json.loads(path.read_text())
    assert r["command"] == "python benchmarks/fake.py --cycles 2" and r["outcome"] == "completed"
    assert r["figures"] == {
        "window": {"rtol": 1e-6, "cycles": 2},
        "steps": [0, 1, 2],
        "sum_check": None,
    }
    assert r["output"] == "a table" and r["cpu_seconds"] >= 0 and r["wall_seconds"] >= 0
    assert path.name == f"{r['started'].replace('-', '').replace(':', '')}-{r['commit']}.json"
    page = (scratch / "RESULTS.md").read_text()
    assert "`python benchmarks/fake.py --cycles 2`" in page and "a table" in page
    assert page.endswith("## Measured by hand\n\nA figure.\n")


def test_a_failed_run_is_recorded_as_failed(scratch):
    with pytest.raises(ValueError, match="boom"), results.recording("benchmarks/fake.py"):
        results.record({"reached": 1})
        raise ValueError("boom")
    (path,) = (scratch / "records" / "fake").glob("*.json")
    r = json.loads(path.read_text())
    assert r["outcome"] == "failed: ValueError: boom" and r["figures"] == {"reached": 1}


def test_records_go_where_workbench_results_says(scratch, monkeypatch):
    monkeypatch.setenv("WORKBENCH_RESULTS", "0")
    with results.recording("benchmarks/fake.py"):
        results.record({"x": 1})
    assert not (scratch / "records").exists() and not (scratch / "RESULTS.md").exists()
    monkeypatch.setenv("WORKBENCH_RESULTS", str(scratch / "elsewhere"))
    with results.recording("benchmarks/fake.py"):
        pass
    assert len(list((scratch / "elsewhere" / "fake").glob("*.json"))) == 1
    assert not (scratch / "RESULTS.md").exists()  # the page shows the repository's records


def test_figures_are_what_json_holds(scratch):
    results.record({"outside": 1})  # outside a recording: goes nowhere
    with results.recording("benchmarks/fake.py"):
        with pytest.raises(TypeError, match=r"figures\['runs'\]\['plain'\] is a \w*Path"):
            results.record({"runs": {"plain": Path("x")}})


#: the figures the docs' tests read from each benchmark's records
#: (tests/records/test_doc_records.py,
#: test_docstring_records.py, test_docs.py): the scripts record them under these names
READ = {
    "tangent_speed.py": ["cycles", "t0", "rtol", "defect", "runs", "cpu_s_per_cycle",
                         "times_plain", "steps_per_cycle", "events_per_cycle",
                         "reorthonormalisations_per_cycle", "sum_check"],
    "lle.py": ["lle", "stderr", "lle_variational", "difference", "stderr_difference",
               "renormalisations", "shrink_renormalisations", "starts", "cycles_per_start",
               "converged", "separations", "mean_difference"],
    "continuation.py": ["continued_sweep", "brute_force", "workers_cpu_min",
                        "longest_segment_min", "wall_min", "load_before", "load_after",
                        "cpu_min_all", "min_on_workers", "cpu_ratio", "newton",
                        "map_jacobian_cpu_s", "derivative_cpu_s", "chaos_map_corners",
                        "lle_stderr"],
}  # fmt: skip


@pytest.mark.parametrize("script", sorted(READ))
def test_the_benchmarks_record_the_figures_the_docs_tests_read(script):
    source = (ROOT / "benchmarks" / script).read_text()
    assert "record(" in source
    assert [k for k in READ[script] if f'"{k}"' not in source] == []
    newest = results.load_records(benchmark=script)[-1]
    assert newest["figures"], f"the newest {script} record has no figures"
