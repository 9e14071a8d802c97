"""Solvers: compiled embedded Runge–Kutta pairs with dense output and events, and scipy's
``solve_ivp`` as the independent reference backend."""

from workbench.solver._simulate import RunResult, integrate, simulate

__all__ = ["RunResult", "integrate", "simulate"]
