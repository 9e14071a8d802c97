"""The nine-bar mechanism with revolute clearance joints (Chen et al. 2019).

Closed-form kinematics (:mod:`._kinematics`), compiled reduced-coordinate dynamics with
Lankarani–Nikravesh contact and modified Coulomb / LuGre friction (:mod:`._dynamics`), and the
``ninebar`` model that scenes use (:mod:`._model`).
"""

from workbench.models.ninebar._model import JOINTS, NineBar
from workbench.models.ninebar._placement import BODY_INDEX, Placement, placement

__all__ = ["BODY_INDEX", "JOINTS", "NineBar", "Placement", "placement"]
