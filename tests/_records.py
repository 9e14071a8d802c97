"""The repository's root and the benchmark records, for the tests that check what docs quote."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NOTES = ROOT / "benchmarks" / "NOTES.md"


def _results_module():
    """benchmarks/_results.py (the records' reader and the results page's generator)."""
    spec = importlib.util.spec_from_file_location(
        "benchmark_results", ROOT / "benchmarks" / "_results.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


results = _results_module()


def records(benchmark: str) -> list[dict]:
    """The records of ``benchmark`` (its script's name), in the order its runs ended."""
    return results.load_records(benchmark=benchmark)
