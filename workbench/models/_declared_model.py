"""The model of a declared linkage: a :class:`~workbench.models._mechanism.Mechanism` like the
built-in ``ninebar`` and ``slider_crank``, whose compiled hooks are generated from the declaration
(:mod:`workbench.models._declared_source`) and whose parameters are the declaration's values.

A scene declares its mechanism in a ``[mechanism]`` table (``model.name = "declared"``, or no
``[model]`` table); Python code calls :func:`declared_model` with a
:class:`~workbench.models._declaration.Linkage`. Either makes the model known to
:func:`workbench.models.get_model` as ``declared_<name>_<digest>`` (the digest of the
declaration, so that two declarations of one name are two models), which is what campaigns,
continuation, analysis and archives look up.

Parameters (SI), each defaulting to the declaration's value:

- ``omega``: the speed of the slowest crank (rad s-1); every crank turns at its declared multiple
  of it (the declared signs kept), so that the forcing period is 2 pi / omega. A crank that a
  motor drives (``drive = "torque"``, the linkage's only crank) starts at that speed instead:
  its angle (rad) and speed (rad s-1) are states after the clearance vectors and their rates,
  its coordinate a free one with the motor's torque as generalised force, its recorded torque
  the motor's, the driver work the integral of that torque times the crank's speed; the model
  then has no forcing period (a run lasts a ``duration``; cycles, strobes and the analyses that
  need a period are refused as for any autonomous model), and at most one joint has a
  clearance at once (the free coordinates' 4 x 4 solve). The motor's constants are compiled
  into the hooks like the geometry;
- ``gravity``, ``gravity_angle``; ``mass_<body>`` of every link and slider and
  ``inertia_<link>`` of every link;
- per clearance joint J: ``clearance_J`` and the contact parameters ``<name>_J`` of
  :data:`JOINT_PARAMETERS` (the built-ins' names: ``restitution_J``, ...);
- the friction parameters of :data:`FRICTION_PARAMETERS` (``friction_coefficient``, ...), which
  the joints share (one friction law per mechanism, as in the built-ins): a declaration whose
  joints declare different ones is refused.

The geometry is compiled into the hooks (a new geometry is a new declaration, compiled anew).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import re
import threading
from typing import ClassVar

import numpy as np

import workbench.models as models
from workbench._errors import SceneError
from workbench.models._base import Effect, Parameter
from workbench.models._clearance import (
    CONTACT_EFFECT,
    FRICTION_EFFECT,
    contact_law,
    energy_outputs,
    joint_block,
    validate_joint,
)
from workbench.models._declaration import CONTACT_PARAMETERS, GROUND, Linkage, to_table
from workbench.models._declared_kinematics import Motion, kinematics
from workbench.models._declared_source import body_rows, generated_source
from workbench.models._mechanism import (
    Mechanism,
    body_parameters,
    mechanism_parameters,
    motor_states,
)

__all__ = ["FRICTION_PARAMETERS", "JOINT_PARAMETERS", "DeclaredMechanism", "declared_model"]

#: the contact parameters each clearance joint has for itself (``<name>_<joint>``)
JOINT_PARAMETERS = (
    "clearance",
    "bearing_radius",
    "youngs_modulus",
    "poisson_ratio",
    "contact_stiffness",
    "contact_exponent",
    "restitution",
    "impact_velocity_floor",
    "hunt_crossley_damping",
    "max_penetration",
)
#: the friction parameters the clearance joints of a mechanism share
FRICTION_PARAMETERS = tuple(n for n in CONTACT_PARAMETERS if n not in JOINT_PARAMETERS)
#: the most clearance joints with a clearance at once (the free accelerations' 4 x 4 solve)
MAX_CLEARANCES = 2

_POS = {"lower": 0.0, "lower_open": True}
_LOCK = threading.Lock()
_MODELS: dict[str, type[DeclaredMechanism]] = {}


class DeclaredMechanism(Mechanism):
    """A mechanism declared as data (:class:`~workbench.models._declaration.Linkage`); the
    subclass of one declaration is made by :func:`declared_model`."""

    #: the declaration
    linkage: ClassVar[Linkage]

    def clearances(self, params) -> dict[str, float]:
        """Clearance of each joint, m."""
        return {j: params[f"clearance_{j}"] for j in self.joints}

    def joint_parameters(self, params, joint: str) -> dict[str, float]:
        """The contact and friction parameters of one joint, by the built-ins' names."""
        out = {n: params[f"{n}_{joint}"] for n in JOINT_PARAMETERS}
        out.update({n: params[n] for n in FRICTION_PARAMETERS})
        return out

    def ideal_motion(self, params, time) -> Motion:
        """The linkage's motion with ideal joints at the times ``time`` (s), every crank turning
        at its declared multiple of ``params["omega"]`` (rad s-1)
        (:func:`workbench.models._declared_kinematics.kinematics`)."""
        slowest = min(abs(c.omega) for c in self.linkage.cranks)
        cranks = tuple(
            dataclasses.replace(c, omega=c.omega / slowest * params["omega"])
            for c in self.linkage.cranks
        )
        return kinematics(dataclasses.replace(self.linkage, cranks=cranks), time)

    def motors(self, params) -> tuple[tuple[str, int, float, float], ...]:
        """The motor-driven cranks: (label, index in q, initial angle (rad), initial speed
        (rad s-1): the crank's declared multiple of ``params["omega"]``)."""
        slowest = min(abs(c.omega) for c in self.linkage.cranks)
        return tuple(
            (c.link, k, c.angle0, c.omega / slowest * params["omega"])
            for k, c in enumerate(self.linkage.cranks)
            if c.torque_driven
        )

    def states(self, effects):
        present = [j for j in self.joints if j in effects["clearance"]]
        # the motors' initial angle and speed do not name the states
        motors = tuple((c.link, 0, 0.0, 0.0) for c in self.linkage.cranks if c.torque_driven)
        return tuple(motor_states(super().states(effects), present, motors))

    def outputs(self, effects):
        out = super().outputs(effects)
        if self.motors({"omega": 1.0}) and not effects["clearance"]:
            out = (*out, *energy_outputs())  # the motor's work with ideal joints
        if self.linkage.sliders:
            return out
        return tuple(q for q in out if not q.name.startswith("slider_"))

    def forcing_period(self, params):
        """2 pi / omega (s) for cranks that turn at constant speeds; None (an autonomous
        system: no forcing period for strobes, transients in periods or cycles) where a
        motor drives the crank, whose speed is then a state."""
        if self.motors(params):
            return None
        return super().forcing_period(params)

    def validate(self, params, effects):
        for j in self.joints:
            validate_joint(
                self.joint_parameters(params, j),
                params[f"clearance_{j}"],
                f"parameters.clearance_{j}",
            )
        if len(effects["clearance"]) > MAX_CLEARANCES:
            raise SceneError(
                "effects.clearance",
                f"got {list(effects['clearance'])!r}; at most {MAX_CLEARANCES} joints of a "
                "declared mechanism have a clearance at once (choose among them)",
            )
        if self.motors(params) and len(effects["clearance"]) > MAX_CLEARANCES - 1:
            raise SceneError(
                "effects.clearance",
                f"got {list(effects['clearance'])!r}; with a motor-driven crank (a free "
                f"coordinate too) at most {MAX_CLEARANCES - 1} joint has a clearance at once",
            )

    def pack(self, params, effects):
        bodies = tuple(b.name for b in (*self.linkage.links, *self.linkage.sliders))
        base = mechanism_parameters(params, effects, bodies)
        extra = len(body_rows(self.linkage)) - len(bodies)  # the marker and the ground
        base["mass"] = [*base["mass"], *[0.0] * extra]
        base["inertia"] = [*base["inertia"], *[0.0] * extra]
        law = contact_law(effects)
        blocks = [
            joint_block(self.joint_parameters(params, j), params[f"clearance_{j}"], law)
            for j in self.joints
        ]
        return self.dynamics.P.pack({**base, "joint": np.concatenate(blocks)})


def _digest(linkage: Linkage) -> str:
    text = json.dumps(to_table(linkage), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _shared_friction(linkage: Linkage) -> dict[str, float]:
    """The friction parameters of the joints, which they share (SceneError naming the first
    joint that differs from the first's)."""
    first = linkage.clearances[0]
    for c in linkage.clearances[1:]:
        for n in FRICTION_PARAMETERS:
            if getattr(c, n) != getattr(first, n):
                raise SceneError(
                    f"{c.key}.{n}",
                    f"got {getattr(c, n)!r}, joint {first.joint!r} has {getattr(first, n)!r}; "
                    "the clearance joints of a mechanism share one friction law's parameters",
                )
    return {n: getattr(first, n) for n in FRICTION_PARAMETERS}


def _parameters(linkage: Linkage) -> tuple[Parameter, ...]:
    slowest = min(abs(c.omega) for c in linkage.cranks)
    links = linkage.links
    sliders = linkage.sliders
    out = body_parameters(
        tuple(b.name for b in (*links, *sliders)),
        [b.mass for b in (*links, *sliders)],
        [b.inertia for b in links] + [0.0] * len(sliders),
    )
    out += [
        Parameter(
            "omega",
            slowest,
            "rad s-1",
            "speed of the slowest crank (the others turn at their declared multiples of it)",
            **_POS,
        ),
        Parameter("gravity", linkage.gravity, "m s-2", "gravitational acceleration", lower=0.0),
        Parameter(
            "gravity_angle",
            linkage.gravity_angle,
            "rad",
            "direction of gravity, counter-clockwise from +X",
        ),
    ]
    for c in linkage.clearances:
        for n in JOINT_PARAMETERS:
            p = CONTACT_PARAMETERS[n]
            out.append(
                dataclasses.replace(
                    p,
                    name=f"{n}_{c.joint}",
                    default=getattr(c, n),
                    long_name=f"{p.long_name} (joint {c.joint})",
                )
            )
    shared = _shared_friction(linkage)
    out += [dataclasses.replace(CONTACT_PARAMETERS[n], default=shared[n]) for n in shared]
    return tuple(out)


def _hooks_module(linkage: Linkage):
    """The generated hooks' module of ``linkage``, loaded (see
    :mod:`workbench.solver._compile`: written into the kernel cache under a name that carries
    the digest of its text, executed from the text)."""
    from workbench._cache import KERNEL_PACKAGE
    from workbench._sources import source_digest
    from workbench.solver._compile import _directory, _load

    source = generated_source(linkage)
    label = "mechanism_" + re.sub(r"\W", "_", linkage.name)
    name = f"{label}_{source_digest(source, f'{KERNEL_PACKAGE}.{label}')}"
    return _load(name, _directory() / f"{name}.py", source)


def declared_model(linkage: Linkage) -> type[DeclaredMechanism]:
    """The registered model of a declaration (made, with its hooks' module, on first use).

    Parameters
    ----------
    linkage : Linkage
        A declaration whose loops close over a cycle
        (:func:`workbench.models._declare.declare`).

    Returns
    -------
    type
        The :class:`DeclaredMechanism` subclass registered as ``declared_<name>_<digest>``
        (``get_model`` finds it by that name).

    Raises
    ------
    SceneError
        A declaration without a clearance joint, whose joints declare different friction
        parameters, or a motor-driven crank among several cranks.
    """
    digest = _digest(linkage)
    with _LOCK:
        cls = _MODELS.get(digest)
        if cls is not None:
            return cls
        if not linkage.clearances:
            raise SceneError(
                "mechanism.clearances",
                "got none; a declared mechanism's dynamics needs at least one clearance joint "
                "(switch it off with effects.clearance = [] for ideal joints)",
            )
        for c in linkage.cranks:
            if c.torque_driven and len(linkage.cranks) > 1:
                raise SceneError(
                    f"{c.key}.drive",
                    f"got 'torque' with {len(linkage.cranks)} cranks; a motor drives a "
                    "linkage of one crank (declare the others' speeds, or drive this one at "
                    'its speed: drive = "speed")',
                )
        parameters = _parameters(linkage)
        joints = tuple(c.joint for c in linkage.clearances)
        has_friction = any(c.friction_coefficient > 0 for c in linkage.clearances)
        effects = (
            Effect("clearance", joints, "subset", "joints with a radial clearance", joints),
            dataclasses.replace(FRICTION_EFFECT, default="coulomb" if has_friction else "none"),
            CONTACT_EFFECT,
            Effect("gravity", True, "bool", "apply gravity"),
        )
        slider = (
            f"position of slider {linkage.sliders[0].name} along its guide"
            if linkage.sliders
            else "(no slider)"
        )
        bearings = ", ".join(
            f"{c.joint} ({c.journal} in {'the ground' if c.bearing == GROUND else c.bearing})"
            for c in linkage.clearances
        )
        namespace = {
            "name": f"declared_{linkage.name}_{digest[:8]}",
            "description": (
                f"declared planar linkage {linkage.name!r}: {len(linkage.links)} links, "
                f"{len(linkage.sliders)} sliders, cranks "
                f"{', '.join(c.link for c in linkage.cranks)}; clearance joints {bearings}"
            ),
            "reference": "declared in the scene's [mechanism] table",
            "parameters": parameters,
            "effects": effects,
            "joints": joints,
            "cranks": tuple(c.link for c in linkage.cranks),
            "slider": slider,
            "assembly": "the mechanism cannot be assembled at this configuration (a loop does "
            "not close)",
            "dynamics": _hooks_module(linkage),
            "linkage": linkage,
            "verification": "workbench.verification._mechanisms:declared_mechanism",
            "__module__": __name__,
        }
        cls = type(f"Declared_{digest[:8]}", (DeclaredMechanism,), namespace)
        models._DECLARED[cls.name] = cls
        _MODELS[digest] = cls
        return cls
