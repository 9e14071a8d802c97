"""The contact events of a mechanism's clearance joints (hooks ``event_values`` and
``apply_event``): per joint with a clearance its penetration, twice (onset and end); at an
onset the normal velocity is held (where the problem holds one: the Lankarani-Nikravesh law;
the Hunt-Crossley law has no memory and no discrete state) and the LuGre bristles reset. The
events are located whatever the law: the solver steps to each contact's onset and end (where
the force law changes form) and counts them."""

from __future__ import annotations

import math

from numba import njit

from workbench.models._mechanism_layouts import (
    JOINT,
)
from workbench.models.contact import (
    onset_velocity,
)


@njit(cache=True)
def contact_event_values(y, p, ip, g, P, IP, n_joints):
    """The event functions of a mechanism's clearance joints (hook ``event_values``): per joint
    with a clearance, g = e - c, its penetration (m), twice: event 2i (rising zero, contact
    onset) and 2i + 1 (falling zero, contact end) of the i-th joint with a clearance."""
    for j in range(n_joints):
        k = ip[IP.slot + j]  # the joint's clearance x and y are y[k], y[k + 1]
        if k >= 0:
            d = math.sqrt(y[k] * y[k] + y[k + 1] * y[k + 1]) - p[P.joint + j * JOINT.size + JOINT.c]
            g[k] = d
            g[k + 1] = d


@njit(cache=True)
def contact_event(k, y, ip, aux, IP, n_joints):
    """Apply event k of :func:`contact_event_values` (hook ``apply_event``): at a contact onset
    hold the normal velocity in aux (where aux has the joint's slot: under the LN law) and
    reset the joint's LuGre bristles; at its end clear it. Returns 0 (the integration goes
    on)."""
    nf = ip[IP.nf]
    slot = k - k % 2
    for j in range(n_joints):
        if ip[IP.slot + j] == slot:
            held = j < aux.size
            if k % 2 == 0:
                if held:
                    aux[j] = onset_velocity(y[slot], y[slot + 1], y[nf + slot], y[nf + slot + 1])
                iz = ip[IP.z + j]
                if iz >= 0:
                    y[iz] = 0.0
            elif held:
                aux[j] = 0.0
    return 0
