"""The slider-crank mechanism with a revolute clearance joint (Flores et al. 2006).

Closed-form kinematics (:mod:`._kinematics`), compiled reduced-coordinate dynamics with
Lankarani–Nikravesh contact and modified Coulomb / LuGre friction (:mod:`._dynamics`), and the
``slider_crank`` model that scenes use (:mod:`._model`); laid out as
:mod:`workbench.models.ninebar`.
"""

from workbench.models.slider_crank._model import JOINTS, SliderCrank

__all__ = ["JOINTS", "SliderCrank"]
