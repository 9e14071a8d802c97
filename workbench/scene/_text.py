"""Reading a scene's text: a file's bytes decoded as UTF-8, the TOML parsed, and the nesting of
its tables and arrays bounded, each failure one :class:`SceneError` line that names the file
(and the key, where there is one)."""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from workbench._errors import SceneError

__all__ = ["MAX_NESTING", "check_nesting", "parse_toml", "read_scene_file"]

#: the deepest nesting of tables and arrays a scene may have, the scene itself being level 1
#: (the scene format uses 3: ``[sweep.continuation]``, ``[sweep]`` with an array of values); a
#: value nested deeper is a mistake or a hostile file, whose parse or repr would exhaust
#: Python's recursion limit
MAX_NESTING = 16


def read_scene_file(path: Path) -> str:
    """The text of the scene file ``path`` (UTF-8, as TOML requires).

    Raises
    ------
    SceneError
        The file cannot be read, or its bytes are not UTF-8 text (naming the byte, its line
        and its column).
    """
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise SceneError(
            "", f"scene file {str(path)!r} cannot be read: {exc.strerror or exc}"
        ) from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        column = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        raise SceneError(
            "",
            f"scene file {str(path)!r} is not UTF-8 text: byte 0x{data[exc.start]:02x} at line "
            f"{line}, column {column} ({exc.reason}); TOML files are UTF-8: save it as UTF-8",
        ) from None


def parse_toml(text: str, where: str) -> dict[str, Any]:
    """The TOML ``text`` as a dict, its nesting checked (:func:`check_nesting`).

    Raises
    ------
    SceneError
        The text is not TOML, or nests tables or arrays deeper than :data:`MAX_NESTING`.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError("", f"{where} is not valid TOML: {exc}") from None
    except RecursionError:  # the reader recurses once per level of nesting
        raise SceneError(
            "",
            f"{where} nests arrays or tables hundreds of levels deep, too deep to read; a scene "
            f"nests at most {MAX_NESTING} levels",
        ) from None
    return check_nesting(data)


def check_nesting(data: Mapping[str, Any]) -> Mapping[str, Any]:
    """``data`` itself, if its tables and arrays nest at most :data:`MAX_NESTING` levels deep
    (checked without recursion); SceneError naming the key where they nest deeper."""
    stack: list[tuple[Any, str, int]] = [(data, "", 1)]  # the scene itself is level 1
    while stack:
        value, key, depth = stack.pop()
        if isinstance(value, Mapping):
            children = [(v, f"{key}.{k}" if key else str(k), depth + 1) for k, v in value.items()]
        elif isinstance(value, list | tuple):
            children = [(v, key, depth + 1) for v in value]
        else:
            continue
        if depth > MAX_NESTING:
            raise SceneError(
                key,
                f"nests tables or arrays more than {MAX_NESTING} levels deep; a scene value is "
                "a number, a string, a table or an array of those (a sweep: an array of "
                "numbers)",
            )
        stack.extend(children)
    return data
