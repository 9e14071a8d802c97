"""Every ```python block of README.md runs (each in a fresh namespace, in a temporary working
directory that sees the repository's studies/). A block whose first lines say
``# requires: MODULE`` is skipped, with that reason, when MODULE is not installed."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BLOCKS = re.findall(r"^```python\n(.*?)^```", (ROOT / "README.md").read_text(), re.S | re.M)


def test_the_readme_has_python_blocks():
    assert len(BLOCKS) >= 2


@pytest.mark.parametrize("code", BLOCKS, ids=[f"block{i}" for i in range(len(BLOCKS))])
def test_readme_block_runs(code, tmp_path, monkeypatch):
    for module in re.findall(r"^# requires: (\w+)", code, re.M):
        pytest.importorskip(module, reason=f"the README block needs the optional {module!r}")
    (tmp_path / "studies").symlink_to(ROOT / "studies")
    monkeypatch.chdir(tmp_path)
    exec(compile(code, str(ROOT / "README.md"), "exec"), {"__name__": "__readme__"})


def test_the_readme_states_the_current_version_and_format():
    import workbench

    text = (ROOT / "README.md").read_text()
    stated = re.search(r"^Version (\S+), archive format (\d+)", text, re.M)
    assert stated, "README.md lost its 'Version X, archive format N' line"
    assert stated.groups() == (workbench.__version__, str(workbench.FORMAT_VERSION))
