"""The public API's docstrings validated with numpydoc (``make lint``; tests/docs/test_docs.py).

The public API is what the API reference renders: the packages its pages under
``docs/reference/`` name (``::: workbench.archive``), each package's ``__all__``, and the
public methods and properties that its classes define. Each docstring is checked with
:func:`numpydoc.validate.validate` for the checks listed in pyproject.toml's
``[tool.numpydoc_validation]``; a Parameters section, where a docstring has one, must name every
parameter of the signature (numpydoc's PR01 there: a docstring may instead describe its
parameters in prose, which numpydoc cannot check).

Run: ``python docs/docstrings.py``; prints one line per finding and exits 1 if there is any.
"""

from __future__ import annotations

import importlib
import inspect
import re
import sys
from pathlib import Path

from numpydoc.docscrape import NumpyDocString
from numpydoc.hooks.validate_docstrings import parse_config
from numpydoc.validate import validate

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "docs" / "reference"


def public_api() -> dict[str, object]:
    """The public objects by their import path (``workbench.archive.open_run``), each once (the
    first path the reference pages give it)."""
    found: dict[str, object] = {}
    seen: set[int] = set()

    def add(name: str, obj: object) -> None:
        if id(obj) not in seen:
            seen.add(id(obj))
            found[name] = obj

    for page in sorted(REFERENCE.glob("*.md")):
        for package in re.findall(r"^::: (\S+)", page.read_text(), re.M):
            module = importlib.import_module(package)
            for name in getattr(module, "__all__", ()):
                obj = getattr(module, name)
                if not (inspect.isfunction(obj) or inspect.isclass(obj)):
                    continue
                add(f"{package}.{name}", obj)
                if inspect.isclass(obj):
                    for attr, member in vars(obj).items():
                        function = member.fget if isinstance(member, property) else member
                        function = getattr(function, "__func__", function)  # class/static
                        own = f"{obj.__qualname__}.{attr}"
                        if not attr.startswith("_") and (
                            isinstance(member, property)
                            or getattr(function, "__qualname__", None) == own
                        ):
                            add(f"{package}.{name}.{attr}", member)
    return found


def _has_parameters_section(obj: object) -> bool:
    if isinstance(obj, property):
        return False
    return bool(NumpyDocString(inspect.getdoc(obj) or "")["Parameters"])


def findings(objects: dict[str, object] | None = None) -> list[str]:
    """One line per finding, ``name: CODE message``, over ``objects`` (import path -> object;
    default :func:`public_api`)."""
    config = parse_config(ROOT)
    objects = public_api() if objects is None else objects
    out = []
    for name, obj in objects.items():
        if config["exclude"] is not None and config["exclude"].search(name):
            continue
        for code, message in validate(name)["errors"]:
            if code in config["checks"] or (code == "PR01" and _has_parameters_section(obj)):
                out.append(f"{name}: {code} {message}")
    return out


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    lines = findings()
    print("\n".join(lines) or f"numpydoc: {len(public_api())} public docstrings valid")
    sys.exit(1 if lines else 0)
