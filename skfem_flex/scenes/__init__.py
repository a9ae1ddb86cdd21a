"""The catalogue of benchmark scenes (DESIGN.md §5).

Each scene is a function returning a :class:`~skfem_flex.scene.Scene`;
``CATALOGUE`` maps its name to the function, and :func:`parameters` lists
its keyword parameters with defaults and units (for ``skfem-flex list``).
"""
from ._registry import CATALOGUE, get, parameters, register
from .particles import pendulum, spring_mass

__all__ = ["CATALOGUE", "get", "parameters", "register", "pendulum", "spring_mass"]
