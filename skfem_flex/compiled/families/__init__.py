r"""Element families of the compiled core: one module per family, registered here.

A family packs the elements of one kind (every revolute-type point constraint of a scene, every
floating-frame body, …) into one record and evaluates them all in one compiled kernel
(:mod:`skfem_flex.compiled.tasks` says what a kernel is asked). A family module provides

``NAME``
    what notices and errors call it ("gravity");
``FORMS``
    the ``compiled_form()`` names of the elements (or constraint blocks) it packs;
``pack(items, packer)``
    a :class:`FamilyPack` from the items (each ``(form, element, where)``, see
    :class:`~skfem_flex.compiled.pack.Packer`);
``kernel()``
    its compiled kernel (:func:`skfem_flex.compiled.registry.compiled_kernel`).

Adding a family is one module and one line in :data:`FAMILY_MODULES`; the loop and the schemes do
not change.
"""
from __future__ import annotations

from collections import namedtuple
from dataclasses import dataclass, field
from importlib import import_module

import numpy as np

__all__ = ["FamilyPack", "FAMILY_MODULES", "family_for", "families", "first_refusal", "bodies_and_gravity",
           "body_family_pack"]

#: every family of the package, by module (imported when first needed: a scene loads only its own)
FAMILY_MODULES = (
    "constant_mass",
    "gravity",
    "point_rows",
    "linear_rows",
    "distance_rows",
    "springs",
    "two_point_springs",
    "point_loads",
    "dampers",
    "floating_frame",
    "exact_beam",
    "director_beam",
    "rotation_beam",
    "rotated_rows",
    "quadratic_rows",
    "product_rows",
    "rotation_drivers",
    "linear_potentials",
    "spatial_loads",
    "spatial_floating_frame",
    "spatial_springs",
    "spatial_torsion",
    "quaternion_bodies",
)


@dataclass
class FamilyPack:
    """What a family hands the scene: its data, the number of elements, and where it couples the
    Newton matrix.

    Attributes
    ----------
    data : NamedTuple of ndarray
        The family's arrays (field order = the kernel's view order).
    count : int
        Number of elements packed.
    couplings : list of ndarray
        Sets of scene coordinates whose rows and columns the family's tangent may couple (each set
        a dense block of the pattern).
    entries : tuple of ndarray, optional
        (rows, cols) of individual coordinate entries, for families whose tangent is sparse within
        its blocks (a large beam).
    rows : list of (int, ndarray)
        Constraint rows the family owns and the coordinates each row's Φ_q may touch.
    finish : callable, optional
        ``finish(layout) -> data``: the data again once the Newton matrix's storage is fixed (families
        that precompute where their entries go).
    """

    data: object
    count: int
    couplings: list = field(default_factory=list)
    entries: tuple = None
    rows: list = field(default_factory=list)
    finish: object = None


_MODULES = {}
_BY_FORM = None


def _module(name):
    mod = _MODULES.get(name)
    if mod is None:
        mod = _MODULES[name] = import_module(f"{__name__}.{name}")
    return mod


def families():
    """Every registered family module."""
    return tuple(_module(name) for name in FAMILY_MODULES)


def family_for(form_name):
    """The family module that packs elements whose ``compiled_form()`` is named ``form_name``, or None."""
    global _BY_FORM
    if _BY_FORM is None:
        _BY_FORM = {}
        for mod in families():
            for f in mod.FORMS:
                _BY_FORM[f] = mod
    return _BY_FORM.get(form_name)


def first_refusal(elements, forms, check):
    """The ValueError that the first of ``elements`` ((element, its scene coordinates) pairs) whose compiled form
    is one of ``forms`` raises from ``check(element, coordinates)``, or None: a family's ``refusal_error``,
    what the Python path raises where the family refused a state."""
    for element, idx in elements:
        form = element.compiled_form() if hasattr(element, "compiled_form") else None
        if form is not None and form[0] in forms:
            try:
                check(element, list(idx))
            except ValueError as exc:
                return exc
    return None


def bodies_and_gravity(items, data_type):
    """A body family's items split into ``[(data, body, offset)]`` (the items whose first entry is a
    ``data_type``) and ``{id(body): g}``, the gravity fields (items ``(("gravity", g), body, offset)``) summed
    per body, m/s²: for the families whose gravity is quadratic in q and which evaluate it themselves."""
    bodies, gravity = [], {}
    for item, body, off in items:
        if isinstance(item, data_type):
            bodies.append((item, body, off))
        else:
            gravity[id(body)] = gravity.get(id(body), 0.0) + np.asarray(item[1], dtype=float)
    return bodies, gravity


def body_family_pack(type_name, bodies):
    """The :class:`FamilyPack` of a family of bodies with dense blocks: its data the bodies' offsets (field
    ``offs``), then each body's records field by field (``b<k>_<name>``), one coupling block per body.

    Parameters
    ----------
    type_name : str
        Name of the data's NamedTuple type.
    bodies : list of (records, offset, size)
        Per body its NamedTuples of arrays (in the order the kernel reads them), the offset of its coordinates
        and their number.
    """
    names, arrays, offs, couplings = ["offs"], [None], [], []
    for b, (records, off, size) in enumerate(bodies):
        for rec in records:
            names += [f"b{b}_{name}" for name in rec._fields]
            arrays += list(rec)
        offs.append(off)
        couplings.append(np.arange(off, off + size, dtype=np.int64))
    arrays[0] = np.asarray(offs, dtype=np.int64)
    return FamilyPack(data=namedtuple(type_name, names)(*arrays), count=len(bodies), couplings=couplings)
