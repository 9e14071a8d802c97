"""A study of the paper: a directory of scenes plus ``study.toml`` (figures, paper values, claims).

Layout of ``studies/<name>/``: one scene per case (``<case>.toml``; a scene with a ``[sweep]`` is
run as a campaign) and ``study.toml`` with

- ``title``, ``section`` (of the paper), ``paper_figures``, optional ``paper_seconds_per_cycle``
  (case -> s, the paper's MATLAB time per crank cycle);
- ``[[figure]]``: ``paper`` (figure number), ``kind`` (``series`` | ``orbit`` | ``phase`` |
  ``poincare`` | ``lle`` | ``bifurcation``), and for ``series`` a ``var`` with an optional
  ``select`` (e.g. ``{crank = "1"}``);
- ``[[paper_value]]``: a number the paper's text reports (``case``, ``var``, ``select``,
  ``statistic`` = ``peak`` (default; the value of largest magnitude) or ``wolf_lle``, ``value``);
- ``[[claim]]``: a qualitative conclusion of the paper in a checkable form (see
  :mod:`workbench.study._claims`).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from workbench.scene import Scene, load_scene

__all__ = ["Study", "available_studies", "load_study", "quick_scene", "STUDIES_DIR"]

STUDIES_DIR = Path(__file__).resolve().parents[2] / "studies"
FIGURE_KINDS = ("series", "orbit", "phase", "poincare", "lle", "bifurcation")
_KEYS = {
    "title",
    "section",
    "paper_figures",
    "paper_seconds_per_cycle",
    "figure",
    "paper_value",
    "claim",
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
    for table in ("paper_value", "claim"):
        for i, entry in enumerate(meta.get(table, [])):
            for key in ("case", "larger", "smaller"):
                if key in entry and entry[key] not in cases:
                    raise ValueError(
                        f"{meta_path}: {table}[{i}].{key} = {entry[key]!r} is not a case of "
                        f"the study; cases: {sorted(cases)}"
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
    )


def quick_scene(scene: Scene) -> Scene:
    """A much shorter version of a case for smoke tests (``--quick``): fewer cycles and, for
    campaigns, four points spanning the same range. Results of a quick run are not evidence."""
    run = dict(scene.run)
    if scene.sweep:
        run.update(cycles=min(run.get("cycles", 6), 6), transient_cycles=4)
        sweep = {k: {"start": v[0], "stop": v[-1], "num": 4} for k, v in scene.sweep.items()}
        return scene.replace(run=run, sweep=sweep)
    if "cycles" in run:
        chaos_like = run["cycles"] > 50
        run.update(cycles=30 if chaos_like else 3, transient_cycles=min(run["transient_cycles"], 2))
    return scene.replace(run=run)
