"""The documentation site (issue 26 item 1): ``mkdocs build --strict`` (every warning an
error, none hidden: issue 40 item 2) into a temporary directory; the public docstrings pass
numpydoc's validation (docs/docstrings.py, which ``make lint`` runs); every ```python block
of its pages runs (each in a fresh namespace, in a temporary working directory that sees the
repository's studies/, data/ and pyproject.toml; ``# requires: MODULE`` skips a block without
MODULE, as in the README); and every ``workbench ...`` line of its ```sh blocks parses with
the command line's own parser (the commands and options the pages show exist)."""

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
PAGES = sorted(p for p in DOCS.rglob("*.md") if not p.is_symlink())
FENCE = re.compile(r"^```(\w+)\n(.*?)^```", re.S | re.M)
#: a block marked ``<!-- file: NAME -->`` or ``<!-- run: NAME -->`` needs its setting: a module
#: of a user's model, or a block that runs with those modules as files (docs/own-models.md:
#: tests/models/test_user_models.py runs them), or the cluster guide's recipe and its lazy
#: analysis of
#: a campaign archive (docs/cluster.md: tests/campaign/test_cluster_recipe.py runs them)
MARKED = re.compile(r"<!-- (?:file|run): \S+ -->\n$")


def _python_blocks(page: Path) -> list[tuple[Path, str]]:
    text = page.read_text()
    return [
        (page, m.group(2))
        for m in FENCE.finditer(text)
        if m.group(1) == "python" and not MARKED.search(text[: m.start()])
    ]


BLOCKS = [block for page in PAGES for block in _python_blocks(page)]
COMMANDS = [
    line
    for page in PAGES + [ROOT / "README.md"]
    for lang, code in FENCE.findall(page.read_text())
    if lang == "sh"
    for line in code.splitlines()
    if line.startswith("workbench ")
]


def test_the_pages_have_blocks():
    assert len(BLOCKS) >= 12 and len(COMMANDS) >= 10


#: a line of mkdocs' log that is a warning or an error (``WARNING -  griffe: ...``)
LOGGED_PROBLEM = re.compile(r"^(WARNING|ERROR)\b.*$", re.M)


def test_site_builds_strict(tmp_path):
    """``make docs``'s build: strict, and without ``-q``, which sets mkdocs' log level to ERROR
    and so hides warnings from strict mode (issue 40 item 2: griffe's warnings on a docstring
    passed here and aborted ``make docs``); a warning in the log fails it too."""
    pytest.importorskip("mkdocs", reason="the 'docs' extra builds the site (make test has it)")
    site = tmp_path / "site"
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(site)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    log = done.stdout + done.stderr
    problems = [m.group(0) for m in LOGGED_PROBLEM.finditer(log)]
    assert done.returncode == 0 and not problems, "\n".join(problems) or log[-3000:]
    # the API reference from the docstrings, the notebooks with their outputs, the report
    assert "wolf_lle" in (site / "reference/analysis/index.html").read_text()
    notebook = (site / "notebooks/02_chaos_identification/index.html").read_text()
    assert "reliable:" in notebook and "Wolf LLE" in notebook  # an output, not only code
    assert "Mann-Whitney" in (site / "studies/report/index.html").read_text()
    assert (site / "results/index.html").is_file() and (site / "changelog/index.html").is_file()


def _id(block):
    page, code = block
    return f"{page.relative_to(DOCS)}:{BLOCKS.index(block)}"


@pytest.mark.parametrize("block", BLOCKS, ids=[_id(b) for b in BLOCKS])
def test_docs_block_runs(block, tmp_path, monkeypatch):
    page, code = block
    for module in re.findall(r"^# requires: (\w+)", code, re.M):
        pytest.importorskip(module, reason=f"the block needs the optional {module!r}")
    for name in ("studies", "data", "pyproject.toml"):
        (tmp_path / name).symlink_to(ROOT / name)
    monkeypatch.chdir(tmp_path)
    exec(compile(code, str(page), "exec"), {"__name__": "__docs__"})


@pytest.mark.parametrize("line", COMMANDS)
def test_docs_command_parses(line):
    from workbench.cli import build_parser

    args = shlex.split(line, comments=True)[1:]
    if args == ["--version"]:
        return
    parsed = build_parser().parse_args(args)
    assert parsed.command == args[0]


@pytest.mark.parametrize("page", [ROOT / "README.md", DOCS / "getting-started.md"], ids=str)
def test_every_command_is_shown(page):
    """The command-line tours list every subcommand ``workbench --help`` has."""
    from workbench.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    shown = {
        line.split()[1]
        for lang, code in FENCE.findall(page.read_text())
        if lang == "sh"
        for line in code.splitlines()
        if line.startswith("workbench ") and not line.startswith("workbench --")
    }
    assert sorted(set(sub.choices) - shown) == [], page.name


def _docs_module(name: str):
    """A script of docs/ (``hooks.py``, ``docstrings.py``) as a module."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(f"docs_{name}", DOCS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_public_docstrings_pass_numpydoc():
    """``make lint``'s docstring check (docs/docstrings.py): the objects the API reference
    renders pass numpydoc's validation with pyproject's checks."""
    pytest.importorskip("numpydoc", reason="the 'test' extra has numpydoc")
    checker = _docs_module("docstrings")
    objects = checker.public_api()
    assert "workbench.archive.open_run" in objects and "workbench.scene.Scene.replace" in objects
    assert checker.findings(objects) == []


BAD_DOCSTRINGS = '''
def paragraph_in_parameters(path, chunks=None):
    """Read it.

    Parameters
    ----------
    path : str
        The file.
    chunks : int or None
        Chunks.

    An archive of an older format is upgraded (the paragraph open_run had here).
    """


def incomplete(x, y):
    """Add.

    Parameters
    ----------
    x : float
        The first.
    """


def in_prose(x, y):
    """Add ``x`` and ``y`` (parameters described in prose: not a finding)."""
'''


def test_the_docstring_check_can_fail(tmp_path, monkeypatch):
    pytest.importorskip("numpydoc", reason="the 'test' extra has numpydoc")
    (tmp_path / "bad_docstrings.py").write_text(BAD_DOCSTRINGS)
    monkeypatch.syspath_prepend(str(tmp_path))
    import bad_docstrings

    checker = _docs_module("docstrings")
    names = ("paragraph_in_parameters", "incomplete", "in_prose")
    found = checker.findings({f"bad_docstrings.{n}": getattr(bad_docstrings, n) for n in names})
    codes = {(line.split(":")[0], line.split()[1]) for line in found}
    assert ("bad_docstrings.paragraph_in_parameters", "PR02") in codes
    assert ("bad_docstrings.incomplete", "PR01") in codes
    assert not any(name == "bad_docstrings.in_prose" for name, _ in codes)


def test_key_figures_are_the_reports():
    """The figures the site commits beside the report (docs/hooks.py) are ones the report cites,
    and each one committed is in that list (make studies copies them from its run)."""
    hooks = _docs_module("hooks")
    cited = set(hooks._CITED.findall((ROOT / "studies" / "REPORT.md").read_text()))
    assert set(hooks.KEY_FIGURES) <= cited
    committed = {str(p.relative_to(hooks.FIGURES)) for p in hooks.FIGURES.rglob("*.png")}
    assert committed <= set(hooks.KEY_FIGURES)


def _newest_continuation_record(figure: str) -> tuple[dict, str, str]:
    """The newest ``continuation.py`` record (benchmarks/records/continuation/) with ``figure``,
    its commit as the page names it ("plus uncommitted changes" where the record's tree was
    dirty), and docs/continuation.md with its whitespace collapsed."""
    from _records import records

    newest = [r for r in records("continuation.py") if figure in r["figures"]][-1]
    sha = newest["commit"].removesuffix("-dirty")
    commit = sha + (" plus uncommitted changes" if newest["commit"] != sha else "")
    return newest["figures"], commit, " ".join((DOCS / "continuation.md").read_text().split())


def test_fig32_cost_is_the_newest_benchmark_record():
    """docs/continuation.md quotes the newest ``continuation.py --parts fig32`` record (the
    cost of the paper's Fig. 32 continued): each number it gives is that record's, as the
    benchmark prints it."""
    figures, commit, page = _newest_continuation_record("continued_sweep")
    sweep, brute = figures["continued_sweep"], figures["brute_force"]
    cpu, longest, wall, load0, load1 = (
        f"{sweep[k]:.1f}"
        for k in ("workers_cpu_min", "longest_segment_min", "wall_min", "load_before", "load_after")
    )
    assert sweep["workers"] == 2 and sweep["points"] == 300
    assert f"at {commit}): the 300 values" in page
    assert f"took {wall} min wall on 2 workers ({cpu} min of the workers' CPU" in page
    assert f"longest segment {longest} min" in page and f"from {load0} to {load1}" in page
    assert (
        f"costs {brute['cpu_min_all']:.1f} min of CPU for all 300, "
        f"{brute['min_on_workers']:.1f} min"
    ) in page
    assert f"takes {brute['cpu_ratio']:.1f}x less CPU" in page
    assert sweep["wall_min"] <= 10.0  # the target (issue 25 item 6)


def test_the_newton_step_cost_is_the_newest_benchmark_record():
    """docs/continuation.md quotes the newest ``continuation.py --parts newton`` record: the CPU
    time of one Newton step on the nine-bar's branch (map and Jacobian, parameter derivative)
    at each omega it measured, and that record's commit."""
    figures, commit, page = _newest_continuation_record("newton")
    steps = figures["newton"]
    omegas = " / ".join(steps)
    maps = " / ".join(f"{s['map_jacobian_cpu_s']:.2f}" for s in steps.values())
    derivatives = " / ".join(f"{s['derivative_cpu_s']:.2f}" for s in steps.values())
    assert f"newton`, at {commit}):" in page
    assert f"costs {maps} s of CPU at omega = {omegas} pi" in page
    assert f"its derivative in omega {derivatives} s more" in page
    assert max(s["map_jacobian_cpu_s"] + s["derivative_cpu_s"] for s in steps.values()) < 10.0


def test_the_templates_page_names_every_tag():
    """docs/internals/templates.md lists the tags the compiler rewrites in the templates."""
    used = {
        tag
        for path in (ROOT / "workbench").rglob("*.py")
        for tag in re.findall(r"@@[A-Z_]+@@", path.read_text())
    }
    named = set(re.findall(r"@@[A-Z_]+@@", (DOCS / "internals" / "templates.md").read_text()))
    assert sorted(used - named) == []
