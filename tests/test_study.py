"""The paper's studies: specs load, a quick run yields paper values, claims, figures, report."""

import json

import pytest

from workbench.cli import main
from workbench.study import available_studies, load_study, run_study, write_report
from workbench.study._claims import evaluate_claim

PAPER_STUDIES = {
    "friction_models",
    "clearance_joints",
    "clearance_size",
    "driving_speed",
    "friction_coefficient",
    "chaos",
    "bifurcation_clearance",
    "bifurcation_speed",
    "bifurcation_friction",
    "high_speed",
}


def test_every_paper_study_is_present_and_valid():
    assert PAPER_STUDIES <= set(available_studies())
    for name in PAPER_STUDIES:
        study = load_study(name)
        assert study.figures, name
        assert all(scene.model == "ninebar" for scene in study.cases.values())


def test_claim_with_unknown_case_is_refused(tmp_path):
    d = tmp_path / "bad"
    d.mkdir()
    (d / "only.toml").write_text('[model]\nname = "duffing"\n')
    (d / "study.toml").write_text(
        'title = "t"\n[[claim]]\ntext = "x"\nvar = "x"\nlarger = "other"\nsmaller = "only"\n'
    )
    with pytest.raises(ValueError, match=r"claim\[0\]\.larger = 'other' is not a case"):
        load_study(d)


def test_claim_logic():
    measures = {"peak": {"a": {"f": -3.0}, "b": {"f": 2.0}}}
    claim = {"text": "a peaks higher", "var": "f", "larger": "a", "smaller": "b"}
    assert evaluate_claim(claim, measures)["reproduced"] is True
    assert evaluate_claim({**claim, "factor": 2.0}, measures)["reproduced"] is False
    near = {**claim, "statistic": "peak_ratio_near_one", "tolerance": 0.6}
    assert evaluate_claim(near, measures)["reproduced"] is True
    missing = {**claim, "var": "g"}
    assert evaluate_claim(missing, measures)["reproduced"] is None


def test_quick_study_run_and_report(tmp_path):
    summary = run_study("friction_models", out=tmp_path, quick=True)
    on_disk = json.loads((tmp_path / "friction_models" / "summary.json").read_text())
    assert on_disk["paper_values"] == json.loads(json.dumps(summary["paper_values"]))
    coulomb = [r for r in summary["paper_values"] if r["case"] == "coulomb"]
    assert {r["quantity"] for r in coulomb} >= {"slider_velocity", "contact_force"}
    # ideal slider peak speed at 2.5 pi is 1.596 m/s (spec); clearances change it little
    v = next(r for r in coulomb if r["quantity"] == "slider_velocity")
    assert abs(v["ours"]) == pytest.approx(1.596, rel=0.05)
    assert all(c["reproduced"] in (True, False) for c in summary["claims"])
    assert len(summary["figures"]) == 5
    for f in summary["figures"]:
        assert (tmp_path / "friction_models" / f.split("/")[-1]).stat().st_size > 10_000
    report = write_report(tmp_path, tmp_path / "REPORT.md").read_text()
    assert "Figs. 4-9" in report and "| coulomb | slider_velocity | -1.938 |" in report
    assert "Not run yet" in report  # the other studies


def test_cli_study_list(capsys):
    assert main(["study", "list"]) == 0
    assert "bifurcation_speed" in capsys.readouterr().out
