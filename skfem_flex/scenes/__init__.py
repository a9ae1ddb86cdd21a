"""The catalogue of benchmark scenes (docs/scenes.md).

Each scene is a function returning a :class:`~skfem_flex.scene.Scene`;
``CATALOGUE`` maps its name to the function, and :func:`parameters` lists
its keyword parameters with defaults and units (for ``skfem-flex list``).
"""
from ._registry import CATALOGUE, get, parameters, register
from .particles import pendulum, spring_mass
from .exact_beams import exact_spin_up_beam, flying_beam, very_flexible_pendulum
from .mechanisms import double_pendulum, flexible_pendulum, free_beam, slider_crank, spin_up_pinned
from .rotating import hub_beam, rotating_beam, rotating_beam_frequencies, spin_up_beam
from .spatial import bricard, heavy_top, rigid_chain, spatial_slider_crank
from .spatial_beams import bend_45, flying_spaghetti_3d, right_angle_frame, spin_up_3d
from .spatial_rotors import rotating_beam_3d, rotor_3d

__all__ = ["CATALOGUE", "get", "parameters", "register", "pendulum", "spring_mass", "exact_spin_up_beam",
           "flying_beam", "very_flexible_pendulum", "double_pendulum", "flexible_pendulum", "free_beam",
           "slider_crank", "spin_up_pinned", "hub_beam", "rotating_beam", "rotating_beam_frequencies",
           "spin_up_beam", "heavy_top", "rigid_chain", "bricard", "spatial_slider_crank", "bend_45",
           "right_angle_frame", "flying_spaghetti_3d", "spin_up_3d", "rotating_beam_3d", "rotor_3d"]
