"""A study of the paper: a directory of scenes plus ``study.toml`` (figures, paper values, claims).

Layout of ``studies/<name>/``: one scene per case (``<case>.toml``; a scene with a ``[sweep]`` is
run as a campaign) and ``study.toml`` with

- ``title``, ``section`` (of the paper), ``paper_figures``, optional ``paper_seconds_per_cycle``
  (case -> s, the paper's MATLAB time per crank cycle) and ``note`` (a sentence the report
  shows under the study's heading, e.g. why its runs are shorter);
- ``realisations`` (integer >= 1, default 1): every case runs as an ensemble of this many
  realisations, a campaign dimension ``realisation`` (:mod:`workbench.run._ensemble`), and
  ``perturbation`` (relative size of the initial-state perturbation, default 1e-9);
- ``[[view]]``: ``name``, ``case`` and ``select`` (e.g. ``{friction_coefficient = 0.1}``): one
  point of a case's parameter sweep, used like a case by claims, paper values and figures;
- ``[[figure]]``: ``paper`` (figure number), ``kind`` (``series`` | ``orbit`` | ``phase`` |
  ``poincare`` | ``lle`` | ``bifurcation`` | ``contact_vs_friction`` | ``energy_balance``),
  and for ``series`` a ``var`` with an optional ``select`` (e.g. ``{crank = "1"}``);
- ``[[paper_value]]``: a number the paper's text reports (``case``, ``var``, ``select``,
  ``statistic`` = ``peak`` (default; the value of largest magnitude) or ``wolf_lle``, ``value``);
- ``[[claim]]``: a qualitative conclusion of the paper in a checkable form (see
  :mod:`workbench.study._claims`), with an optional ``reason`` (the cause shown, with its
  evidence, when the claim is not reproduced), ``why`` (the physics behind the outcome, shown
  with its evidence whatever the verdict) and ``evidence`` (``contact``, ``strobe_contact`` or
  ``friction_law``: which measured numbers support the reason);
- ``[flutter]``: the friction-coefficient study's flutter analysis (``parameter``, ``cases``,
  ``method``): the Jacobian's eigenvalues at continuous contact against the parameter;
- ``[route]``: beyond the paper, how the motion of a bifurcation study becomes chaotic: its sweep
  continued both ways, the periodic orbit's branch and its bifurcations, exponents
  (:mod:`workbench.study._route`; keys :data:`ROUTE_KEYS`).
"""

from __future__ import annotations

import dataclasses
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from workbench.run import DEFAULT_PERTURBATION
from workbench.scene import MAX_PERTURBATION, RUN_SWEEP_KEYS, Scene, load_scene

__all__ = [
    "ROUTE_KEYS",
    "Study",
    "available_studies",
    "load_study",
    "quick_study",
    "quick_scene",
    "parameter_sweep",
    "REPOSITORY_STUDIES",
    "STUDIES_DIR",
    "report_path",
]

# The scenes of the studies ship inside the package (package data, so that an installed wheel
# has them); in the repository the directory is a link to the top-level ``studies/``, the one
# place they are edited.
STUDIES_DIR = Path(__file__).resolve().parent / "scenes"
#: the repository's ``studies/`` (absent from an installed package), where REPORT.md lives
REPOSITORY_STUDIES = Path(__file__).resolve().parents[2] / "studies"
FIGURE_KINDS = (
    "series",
    "orbit",
    "phase",
    "poincare",
    "lle",
    "bifurcation",
    "contact_vs_friction",
    "energy_balance",
)
EVIDENCE_KINDS = ("contact", "strobe_contact", "friction_law")
#: keys of a study's ``[route]`` table (see :mod:`workbench.study._route`)
ROUTE_KEYS = (
    "case",
    "segments",
    "transient_cycles",
    "cycles",
    "method",
    "branch_start",
    "branch_stop",
    "branch_points",
    "branch_max_step",
    "exponents",
    "refine",
    "end_transient_cycles",
    "end_branch_points",
    "end_max_step",
    "end_other_contact",
)
QUICK_REALISATIONS = 4  # the fewest for which the two-sample rank test can reach p < 0.05
_KEYS = {
    "title",
    "section",
    "paper_figures",
    "paper_seconds_per_cycle",
    "realisations",
    "perturbation",
    "view",
    "figure",
    "paper_value",
    "claim",
    "flutter",
    "route",
    "note",
}


@dataclass(frozen=True)
class Study:
    """One study: its cases (scenes by name) and what to compare with the paper."""

    name: str
    directory: Path
    title: str
    section: str
    paper_figures: str
    cases: dict[str, Scene]
    figures: list[dict] = field(default_factory=list)
    paper_values: list[dict] = field(default_factory=list)
    claims: list[dict] = field(default_factory=list)
    paper_seconds_per_cycle: dict[str, float] = field(default_factory=dict)
    realisations: int = 1
    perturbation: float = DEFAULT_PERTURBATION
    views: dict[str, dict] = field(default_factory=dict)
    flutter: dict = field(default_factory=dict)
    route: dict = field(default_factory=dict)
    note: str = ""

    @property
    def members(self) -> list[str]:
        """The single-point cases (no parameter sweep) and the views: what claims compare."""
        single = [c for c, s in self.cases.items() if not parameter_sweep(s)]
        return single + list(self.views)

    def member_scene(self, name: str) -> Scene:
        """The scene of a case or a view (a view: its case at the selected parameters)."""
        if name in self.views:
            v = self.views[name]
            return self.cases[v["case"]].with_parameters(**v["select"])
        return self.cases[name]


def report_path(out: str | Path) -> Path:
    """Where the report goes by default: ``studies/REPORT.md`` in the repository (beside the
    studies it reports on), else ``<out>/REPORT.md`` (an installed package is no place to
    write)."""
    if STUDIES_DIR.resolve() == REPOSITORY_STUDIES.resolve():
        return REPOSITORY_STUDIES / "REPORT.md"
    return Path(out) / "REPORT.md"


def available_studies(root: Path = STUDIES_DIR) -> list[str]:
    """Names of the study directories under ``root`` (those holding a ``study.toml``)."""
    return sorted(p.parent.name for p in Path(root).glob("*/study.toml"))


def load_study(name: str | Path, root: Path = STUDIES_DIR) -> Study:
    """Load ``studies/<name>/`` (or a directory path) and validate it.

    Raises ValueError naming the file, the key, the value and what is allowed.
    """
    directory = Path(name) if Path(name).is_dir() else Path(root) / str(name)
    meta_path = directory / "study.toml"
    if not meta_path.is_file():
        raise ValueError(
            f"no study {str(name)!r}: {str(meta_path)!r} does not exist; available: "
            f"{', '.join(available_studies(root))}"
        )
    meta = tomllib.loads(meta_path.read_text())
    unknown = sorted(set(meta) - _KEYS)
    if unknown:
        raise ValueError(f"{meta_path}: unknown keys {unknown!r}; allowed: {sorted(_KEYS)}")
    cases = {
        p.stem: load_scene(p) for p in sorted(directory.glob("*.toml")) if p.name != "study.toml"
    }
    if not cases:
        raise ValueError(f"{directory}: a study needs at least one scene file (<case>.toml)")
    for i, fig in enumerate(meta.get("figure", [])):
        if fig.get("kind") not in FIGURE_KINDS:
            raise ValueError(
                f"{meta_path}: figure[{i}].kind = {fig.get('kind')!r}; allowed: {FIGURE_KINDS}"
            )
    realisations = meta.get("realisations", 1)
    if isinstance(realisations, bool) or not isinstance(realisations, int) or realisations < 1:
        raise ValueError(
            f"{meta_path}: realisations = {realisations!r}; allowed: an integer >= 1 (the "
            "size of each case's ensemble)"
        )
    perturbation = meta.get("perturbation", DEFAULT_PERTURBATION)
    if (
        isinstance(perturbation, bool)
        or not isinstance(perturbation, int | float)
        or not 0 < perturbation <= MAX_PERTURBATION
    ):
        raise ValueError(
            f"{meta_path}: perturbation = {perturbation!r}; allowed: a number in "
            f"(0, {MAX_PERTURBATION:g}] (relative to each state's characteristic size)"
        )
    views = _views(meta_path, meta.get("view", []), cases)
    members = {**{c: s for c, s in cases.items() if not parameter_sweep(s)}, **views}
    for table in ("paper_value", "claim"):
        for i, entry in enumerate(meta.get(table, [])):
            for key in ("case", "larger", "smaller"):
                if key in entry and entry[key] not in members:
                    raise ValueError(
                        f"{meta_path}: {table}[{i}].{key} = {entry[key]!r} is not a case of "
                        f"the study without a parameter sweep, nor a view; allowed: "
                        f"{sorted(members)}"
                    )
            kind = entry.get("evidence")
            if kind is not None and kind not in EVIDENCE_KINDS:
                raise ValueError(
                    f"{meta_path}: {table}[{i}].evidence = {kind!r}; allowed: {EVIDENCE_KINDS}"
                )
    route = dict(meta.get("route", {}))
    unknown = sorted(set(route) - set(ROUTE_KEYS))
    if unknown:
        raise ValueError(f"{meta_path}: route: unknown keys {unknown!r}; allowed: {ROUTE_KEYS}")
    swept = sorted(c for c, s in cases.items() if parameter_sweep(s))
    if route and route.get("case", swept[0] if swept else None) not in swept:
        raise ValueError(
            f"{meta_path}: route.case = {route.get('case')!r}; allowed: a case with a "
            f"parameter sweep, {swept}"
        )
    return Study(
        name=directory.name,
        directory=directory,
        title=meta.get("title", directory.name),
        section=str(meta.get("section", "")),
        paper_figures=str(meta.get("paper_figures", "")),
        cases=cases,
        figures=list(meta.get("figure", [])),
        paper_values=list(meta.get("paper_value", [])),
        claims=list(meta.get("claim", [])),
        paper_seconds_per_cycle=dict(meta.get("paper_seconds_per_cycle", {})),
        realisations=realisations,
        perturbation=float(perturbation),
        views={name: {"case": v["case"], "select": v["select"]} for name, v in views.items()},
        flutter=dict(meta.get("flutter", {})),
        route=route,
        note=str(meta.get("note", "")),
    )


def parameter_sweep(scene: Scene) -> dict[str, tuple[float, ...]]:
    """The swept model parameters of a scene (its ``[sweep]`` without ``realisation``)."""
    return {k: v for k, v in scene.sweep.items() if k not in RUN_SWEEP_KEYS}


def _views(meta_path: Path, entries: list, cases: dict[str, Scene]) -> dict[str, dict]:
    """Validate the ``[[view]]`` tables: a name that is no case, a swept case, and one value of
    each of its swept parameters."""
    views = {}
    for i, v in enumerate(entries):
        where = f"{meta_path}: view[{i}]"
        name, case, select = v.get("name"), v.get("case"), v.get("select")
        if not isinstance(name, str) or name in cases or name in views:
            raise ValueError(f"{where}.name = {name!r}; allowed: a new name, not a case's")
        if case not in cases or not parameter_sweep(cases[case]):
            swept = sorted(c for c, s in cases.items() if parameter_sweep(s))
            raise ValueError(f"{where}.case = {case!r}; allowed: a case with a sweep, {swept}")
        sweep = parameter_sweep(cases[case])
        if not isinstance(select, dict) or set(select) != set(sweep):
            raise ValueError(
                f"{where}.select = {select!r}; allowed: one value of each swept parameter "
                f"{sorted(sweep)}"
            )
        for k, x in select.items():
            if not any(abs(x - y) <= 1e-12 * max(abs(y), 1e-300) for y in sweep[k]):
                raise ValueError(
                    f"{where}.select.{k} = {x!r} is not a swept value; allowed: {list(sweep[k])}"
                )
        views[name] = {"case": case, "select": {k: float(x) for k, x in select.items()}}
    return views


def quick_study(study: Study) -> Study:
    """The study with every case shortened by :func:`quick_scene` (keeping the swept values its
    views select) and at most :data:`QUICK_REALISATIONS` realisations. Not evidence."""
    keep: dict[str, dict[str, list[float]]] = {}
    for v in study.views.values():
        for k, x in v["select"].items():
            keep.setdefault(v["case"], {}).setdefault(k, []).append(x)
    cases = {c: quick_scene(s, keep.get(c, {})) for c, s in study.cases.items()}
    return dataclasses.replace(
        study, cases=cases, realisations=min(study.realisations, QUICK_REALISATIONS)
    )


def quick_scene(scene: Scene, keep: dict[str, list[float]] | None = None) -> Scene:
    """A much shorter version of a case for smoke tests (``--quick``): fewer cycles and, for
    campaigns, four points spanning the same range (a swept list: its first and last values
    and those in ``keep``) and at most 4 transient cycles. Results of a quick run are not
    evidence."""
    run = dict(scene.run)
    if parameter_sweep(scene):
        dense = scene.record.get("samples_per_period", 1) > 10  # time series, not strobes
        run.update(
            cycles=min(run.get("cycles", 6), 3 if dense else 6),
            transient_cycles=min(run.get("transient_cycles", 4), 4),
        )
        sweep = {}
        for k, v in parameter_sweep(scene).items():
            if k in (keep or {}):
                sweep[k] = sorted({v[0], v[-1], *keep[k]})
            else:
                sweep[k] = {"start": v[0], "stop": v[-1], "num": 4}
        return scene.replace(run=run, sweep=sweep)
    if "cycles" in run:
        chaos_like = run["cycles"] > 50
        run.update(cycles=30 if chaos_like else 3, transient_cycles=min(run["transient_cycles"], 2))
    return scene.replace(run=run)
