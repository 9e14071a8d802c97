"""Scenes: the declarative description of a run (TOML), validated against its model and frozen.

:func:`load_scene` takes a :class:`Scene`, a TOML file path or a mapping; TOML text goes through
:func:`scene_from_toml`. Every error (:class:`~workbench.SceneError`) names the offending key as a
dotted path, shows the value and says what is allowed.
"""

from workbench._errors import SceneError
from workbench.scene._scene import Scene, SceneSource, load_scene, scene_from_toml
from workbench.scene._tables import CONTINUATION_DIRECTIONS, MAX_PERTURBATION, RUN_SWEEP_KEYS

__all__ = [
    "CONTINUATION_DIRECTIONS",
    "MAX_PERTURBATION",
    "RUN_SWEEP_KEYS",
    "Scene",
    "SceneError",
    "SceneSource",
    "load_scene",
    "scene_from_toml",
]
