"""The nine-bar mechanism with revolute clearance joints (Chen et al. 2019).

Closed-form kinematics (:mod:`._kinematics`), compiled reduced-coordinate dynamics with
Lankarani–Nikravesh contact and modified Coulomb / LuGre friction (:mod:`._dynamics`), and the
``ninebar`` model that scenes use (:mod:`._model`).
"""

from workbench.models.ninebar._model import JOINTS, NineBar

__all__ = ["JOINTS", "NineBar"]
