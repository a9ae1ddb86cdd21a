"""Result of a simulation: time histories as arrays."""
from __future__ import annotations

import json
import zipfile
import zlib
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from .files import write_atomically

__all__ = ["Result"]


@dataclass
class Result:
    """Histories recorded at the output steps of a run (SI units).

    Attributes
    ----------
    t : ndarray (n,)
        Times, s.
    q, v : ndarray (n, n_dofs)
        Coordinates and velocities.
    lam : ndarray (n, n_constraints)
        Lagrange multipliers (energy-momentum: mean over the step ending there).
    kinetic, potential, total_energy : ndarray (n,)
        T, V and T + V, J.
    external_work : ndarray (n,)
        Work done since t = 0 by non-conservative loads, prescribed motion and
        drivers, J; the energy balance is total_energy − total_energy[0] = external_work.
    constraint_residual : ndarray (n,)
        ‖Φ(q, t)‖_∞ after each step.
    velocity_constraint_residual : ndarray (n,)
        ‖Φ_q v + Φ_t‖_∞.
    newton_iterations : ndarray (n,)
        Newton iterations spent on the steps ending at each output time.
    prescribed_force : ndarray (n, n_prescribed)
        Generalized force exerted by prescribed-coordinate laws.
    linear_momentum : ndarray (n, 2) or None
    angular_momentum : ndarray (n,) or None
        About the global origin; None when a body does not provide it.
    probes : dict of str to ndarray
        Probe histories, first axis time.
    reactions : dict of str to ndarray
        Joint reactions from the multipliers, constraint name → (n, k) array
        in the global frame: (F_x, F_y) in N that a Pin, Revolute or Slider
        exerts on its (first) body, (F_x, F_y, M) for Weld and Prismatic,
        the generalized force −λ for a Driver (N m on an angle) and for
        user constraints (see each constraint's ``reaction``).
        Energy-momentum: the mean over the step ending there.
    wall_time : float
        Seconds spent in the time loop.
    scheme : str
    dt : float
        Nominal step, s.
    steps : int
        Steps taken (halved steps count as one).
    halvings : int
        Steps that had to be split to converge.
    completed : bool
        False when the run stopped early (the exception carries this result).
    stopped : str
        Why a run that is not completed stopped ("interrupted at t = … s", "diverged at t = … s",
        a Newton failure); "" for a completed run.
    compile_time : float
        Seconds spent compiling the Numba kernels on a first run (a cold cache); not part of
        ``wall_time``.
    run_path : dict or None
        Which code ran: ``loop`` ("compiled"), the linear ``solver`` and matrix ``storage``, and
        ``python_elements``: each element that ran through its own Python methods and why (no compiled
        form; ``compiled=False``).
    final_state : dict or None
        What the integrator carries from one step to the next at the last step done: ``t``,
        ``q``, ``v``, ``acc``, ``pseudo`` (generalized-α), ``lam``, ``prescribed_force``, the
        accumulated ``work``, the ``step`` number and ``halvings``. ``simulate(..., resume=result)``
        continues from it.
    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    lam: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    total_energy: np.ndarray
    external_work: np.ndarray
    constraint_residual: np.ndarray
    velocity_constraint_residual: np.ndarray
    newton_iterations: np.ndarray
    prescribed_force: np.ndarray
    linear_momentum: np.ndarray = None
    angular_momentum: np.ndarray = None
    probes: dict = field(default_factory=dict)
    reactions: dict = field(default_factory=dict)
    wall_time: float = 0.0
    scheme: str = ""
    dt: float = 0.0
    steps: int = 0
    halvings: int = 0
    completed: bool = True
    stopped: str = ""
    compile_time: float = 0.0
    final_state: dict = None
    run_path: dict = None

    @property
    def energy_balance_error(self):
        """total_energy − total_energy[0] − external_work, J."""
        return self.total_energy - self.total_energy[0] - self.external_work

    def relative_energy_error(self, reference=None):
        """max abs(energy balance error) / reference (default: max(abs(T) + abs(V)) over the run)."""
        if reference is None:
            reference = float(np.max(np.abs(self.kinetic) + np.abs(self.potential)))
        return float(np.max(np.abs(self.energy_balance_error))) / max(reference, 1e-300)

    def array_fields(self):
        """Names of the array-valued attributes."""
        return [f.name for f in fields(self) if isinstance(getattr(self, f.name), np.ndarray)]

    # ----------------------------------------------------------- persistence
    def save(self, path):
        """Write every field to a NumPy ``.npz`` archive (written to a temporary file, then renamed).

        Arrays are stored as they are (exact round trip, dtype kept); scalars,
        strings, None and the layout of dicts (``probes`` and any other
        dict-of-arrays field) go into a JSON header. Generic over the
        dataclass fields, so fields added later are saved too.

        Parameters
        ----------
        path : str or Path
            ``.npz`` is appended when the name has another suffix.

        Returns
        -------
        Path
            The file written.

        Raises
        ------
        TypeError
            If a field holds a value that is neither an array, a number, a
            string, None, nor a dict/list/tuple of those.
        """
        path = Path(path)
        if path.suffix != ".npz":
            path = path.with_name(path.name + ".npz")
        arrays = {}
        spec = {"format": _RESULT_FORMAT,
                "fields": {f.name: _encode(getattr(self, f.name), arrays, f.name) for f in fields(self)}}
        def write(tmp):
            with open(tmp, "wb") as fh:
                np.savez(fh, __result__=np.array(json.dumps(spec)), **arrays)
        return write_atomically(path, write)

    @classmethod
    def load(cls, path):
        """Read a :class:`Result` written by :meth:`save` (also a run's ``checkpoint.npz``).

        Fields missing from the file take their defaults; fields the file has
        but this class does not know are ignored. Nothing is ever unpickled.

        Raises
        ------
        FileNotFoundError
            If there is no such file.
        ValueError
            Naming the file and what is wrong when it is not a complete saved
            Result: not an ``.npz`` archive, truncated or damaged, no Result
            header, a required field missing, or histories of unequal length.
        """
        path = Path(path)
        if not path.exists():
            raise FileNotFoundError(f"no result file {str(path)!r}")
        what = f"{str(path)!r} is not a saved (complete) skfem_flex Result file"
        try:
            with np.load(path, allow_pickle=False) as z:
                if not hasattr(z, "files"):
                    raise ValueError("it holds a single array, not an .npz archive")
                if "__result__" not in z.files:
                    raise ValueError("no __result__ header")
                spec = json.loads(str(z["__result__"]))
                if not isinstance(spec, dict) or spec.get("format") != _RESULT_FORMAT:
                    raise ValueError(f"unknown format {spec.get('format') if isinstance(spec, dict) else spec!r}")
                stored = spec.get("fields", {})
                kwargs = {f.name: _decode(stored[f.name], z) for f in fields(cls) if f.name in stored}
        except FileNotFoundError:
            raise
        except (ValueError, KeyError, TypeError, EOFError, OSError, zipfile.BadZipFile, zlib.error) as exc:
            reason = "not a NumPy .npz archive" if "pickle" in str(exc) else _one_line(exc) or type(exc).__name__
            raise ValueError(f"{what}: {reason}") from None
        try:
            res = cls(**kwargs)
        except TypeError as exc:
            raise ValueError(f"{what}: {_one_line(exc)}") from None
        n = np.shape(res.t)[0] if np.ndim(res.t) else -1
        for name in ("q", "v", "kinetic", "potential", "total_energy", "external_work", "newton_iterations"):
            a = getattr(res, name)
            if not isinstance(a, np.ndarray) or a.ndim == 0 or a.shape[0] != n:
                raise ValueError(f"{what}: history {name!r} does not have one entry per time ({n})")
        return res

    def probes_to_csv(self, path):
        """Write the probe histories as CSV (temporary file, then rename): a column ``t`` (s), then one
        per probe component.

        A scalar probe gives a column named after it, a vector probe columns
        ``name[0]``, ``name[1]``, ... (higher dimensions flattened in C order).
        Numbers are written with 17 significant digits.

        Returns
        -------
        Path
        """
        path = Path(path)
        names, cols = ["t"], [np.asarray(self.t, dtype=float)[:, None]]
        for k, val in self.probes.items():
            a = np.asarray(val, dtype=float).reshape(len(self.t), -1)
            if np.ndim(val) == 1:
                names.append(str(k))
            else:
                names.extend(f"{k}[{i}]" for i in range(a.shape[1]))
            cols.append(a)
        return write_atomically(path, lambda tmp: np.savetxt(tmp, np.hstack(cols), delimiter=",",
                                                              header=",".join(names), comments="", fmt="%.17g"))


_RESULT_FORMAT = "skfem_flex.Result/1"


def _one_line(exc):
    return " ".join(str(exc).split())


def _encode(value, arrays, where):
    """JSON description of ``value``; arrays go into ``arrays`` under generated keys."""
    if value is None:
        return {"kind": "none"}
    if isinstance(value, np.ndarray):
        if value.dtype.hasobject:
            raise TypeError(f"Result field {where!r} is an object array, which cannot be saved")
        key = f"a{len(arrays)}"
        arrays[key] = value
        return {"kind": "array", "key": key}
    if isinstance(value, dict):
        items = []
        for k, v in value.items():
            if isinstance(k, (bool, np.bool_)) or not isinstance(k, (str, int, np.integer)):
                raise TypeError(f"Result field {where!r} has a dict key {k!r}; only str and int keys can be saved")
            k = k if isinstance(k, str) else int(k)
            items.append([k, _encode(v, arrays, f"{where}[{k!r}]")])
        return {"kind": "dict", "items": items}
    if isinstance(value, (list, tuple)):
        return {"kind": type(value).__name__, "items": [_encode(v, arrays, f"{where}[{i}]")
                                                      for i, v in enumerate(value)]}
    if isinstance(value, np.generic):
        return {"kind": "scalar", "dtype": value.dtype.str, "value": value.item()}
    if isinstance(value, (bool, int, float, str)):
        return {"kind": "value", "value": value}
    raise TypeError(f"Result field {where!r} holds a {type(value).__name__}, which cannot be saved")


def _decode(spec, z):
    kind = spec["kind"]
    if kind == "none":
        return None
    if kind == "array":
        return z[spec["key"]]
    if kind == "dict":
        return {k: _decode(v, z) for k, v in spec["items"]}
    if kind in ("list", "tuple"):
        items = [_decode(v, z) for v in spec["items"]]
        return items if kind == "list" else tuple(items)
    if kind == "scalar":
        return np.dtype(spec["dtype"]).type(spec["value"])
    return spec["value"]
