"""Helpers shared by the test modules: one copy of each, imported as ``from helpers import ...``.

The tests are not a package; pytest puts this folder on ``sys.path`` (rootdir-relative "prepend"
import mode), so every test module can import this one by name.
"""
import importlib.util
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sps
import skfem

import skfem_flex as sf
from skfem_flex.compiled import ahead

#: the repository's root folder
ROOT = Path(__file__).resolve().parents[1]

#: the spin-up beam's section (Simo & Vu-Quoc 1986): EA (N), EI (N m²), kGA (N), ρA (kg/m), ρI (kg m)
SPIN_UP_SECTION = dict(EA=2.8e7, EI=1.4e4, kGA=1e7, rhoA=1.2, rhoI=6e-4)

#: the flying beam's section (Simo & Vu-Quoc 1986, part II), for the geometrically exact beam
FLYING_BEAM_SECTION = sf.Section(EA=1e4, EI=100.0, kGA=3e3, rhoA=1.0, rhoI=10.0)


#: λ = Ω √(ρA L⁴/EI) and the first flapwise and lead-lag ω √(ρA L⁴/EI) of a uniform Euler–Bernoulli cantilever
#: spinning about an axis through its root (the classical tables of Wright, Smith, Thresher & Wang 1982 and
#: Hodges & Rutkowski 1981, to their 4 decimals; lead-lag² = flap² − λ² for this model)
ROTATING_TABLE = [(0.0, 3.5160, 3.5160), (1.0, 3.6816, 3.5432), (3.0, 4.7973, 3.7435), (6.0, 7.3604, 4.2632),
                  (9.0, 10.2257, 4.8543), (12.0, 13.1702, 5.4270)]


# ------------------------------------------------------------------ arrays
def dense(a):
    """``a`` as a dense float array (sparse matrices converted)."""
    return a.toarray() if sps.issparse(a) else np.asarray(a, dtype=float)


def relerr(a, b):
    """max |a − b| / max |b| (dense or sparse; a zero ``b`` divides by 1e-300)."""
    a, b = dense(a), dense(b)
    return np.abs(a - b).max() / max(np.abs(b).max(), 1e-300)


def central_jacobian(fun, x, h=1e-6):
    """∂fun/∂x by central differences: columns (fun(x + h e_k) − fun(x − h e_k)) / 2h."""
    cols = []
    for k in range(x.size):
        e = np.zeros_like(x)
        e[k] = h
        cols.append((np.atleast_1d(fun(x + e)) - np.atleast_1d(fun(x - e))) / (2 * h))
    return np.array(cols).T


def crossing_times(t, x, xdot):
    """Times where x crosses 0 upwards, located by cubic Hermite interpolation on each step (O(dt⁴))."""
    out = []
    for i in np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]:
        h = t[i + 1] - t[i]
        p0, p1, m0, m1 = x[i], x[i + 1], xdot[i] * h, xdot[i + 1] * h

        def herm(s):
            return ((2 * s ** 3 - 3 * s ** 2 + 1) * p0 + (s ** 3 - 2 * s ** 2 + s) * m0
                    + (-2 * s ** 3 + 3 * s ** 2) * p1 + (s ** 3 - s ** 2) * m1)
        lo, hi = 0.0, 1.0
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if herm(mid) < 0:
                lo = mid
            else:
                hi = mid
        out.append(t[i] + 0.5 * (lo + hi) * h)
    return np.array(out)


def bordered_matrix(n, n_frame=3, n_mult=2, half_band=3, seed=0):
    """Band (SPD-like) elastic block, dense frame rows and columns, multipliers touching far coordinates."""
    rng = np.random.default_rng(seed)
    nb = n_frame + n
    offsets = range(-half_band, half_band + 1)
    band = sps.diags([rng.normal(size=n - abs(k)) for k in offsets], list(offsets), shape=(n, n)).tocsr()
    band = band + band.T + sps.identity(n) * (4.0 * half_band + 2.0)
    frame = rng.normal(size=(n_frame, n))
    top = np.hstack([rng.normal(size=(n_frame, n_frame)) + 10 * np.eye(n_frame), frame])
    body = sps.vstack([sps.csr_matrix(top), sps.hstack([sps.csr_matrix(frame.T), band])]).tocsr()
    cols = np.concatenate([np.arange(n_frame), [n_frame + n // 2, nb - 1]])    # far-apart coordinates
    c = np.zeros((n_mult, nb))
    c[:, cols[:n_frame + 2]] = rng.normal(size=(n_mult, cols[:n_frame + 2].size))
    return sps.bmat([[body, sps.csr_matrix(c).T], [sps.csr_matrix(c), None]], format="csc")


# ------------------------------------------------------------------ floating-frame bodies
def floating_beam(n_elements, reference, strain, order, sparse, section=SPIN_UP_SECTION):
    """A FloatingBeam on a uniform mesh of [0, 10 m] with ``section`` (a dict of Section's arguments)."""
    from skfem_flex.bodies.floating.body import FloatingBeam

    beam = sf.TimoshenkoBeam(skfem.MeshLine(np.linspace(0.0, 10.0, n_elements + 1)), sf.Section(**section),
                             order=order)
    return FloatingBeam(beam, reference=reference, strain=strain, sparse=sparse)


def random_floating_states(body, rng, scale, step):
    """(q0, q1, v0, v1) of a floating-frame body: frame coordinates of order 1, elastic ones of size
    ``scale``, q1 − q0 of size ``step``, the angle increment tiny or large (both branches of sinc(Δθ/2))."""
    n = body.n_dofs
    q0 = rng.normal(size=n) * scale
    q0[:3] = rng.normal(size=3) * [1.0, 1.0, 3.0]
    q1 = q0 + rng.normal(size=n) * step
    q1[2] = q0[2] + rng.choice([1e-5, 0.3])
    v0, v1 = rng.normal(size=n), rng.normal(size=n)
    return q0, q1, v0, v1


def contract_terms(body, q0, q1, v0, v1, dt):
    """The energy-momentum step's fused terms (p1, kinetic and potential discrete gradients, Newton matrix,
    round-off floor) assembled from the body's separate numpy contract methods (the scene's general path)."""
    gk, gk_q, gk_v = body.kinetic_discrete_gradient(q0, q1, v0, v1)
    gp, gp_q = body.potential_discrete_gradient(q0, q1)
    M1 = dense(body.mass_matrix(q1))
    jac = ((2.0 / dt) * M1 + dense(body.momentum_jacobian(q1, v1)) - dt * dense(gk_q) - 2.0 * dense(gk_v)
           + dt * dense(gp_q))
    floor = dt * (np.abs(dense(gp_q)) @ (np.abs(q0) + np.abs(q1)))
    return M1 @ v1, gk, gp, jac, floor


# ------------------------------------------------------------------ runs
def assert_same_run(a, b, q_tol=1e-9, v_tol=1e-7, e_tol=None):
    """Compiled run a against Python run b: states to ``q_tol`` and ``v_tol`` (v1 = 2Δq/Δt − v0 amplifies
    round-off), energies, work, momenta and reactions to ``e_tol`` (default ``v_tol``), relative."""
    e_tol = v_tol if e_tol is None else e_tol
    np.testing.assert_array_equal(a.t, b.t)
    assert a.steps == b.steps and a.halvings == b.halvings
    assert np.abs(a.q - b.q).max() <= q_tol * np.abs(b.q).max()
    assert np.abs(a.v - b.v).max() <= v_tol * np.abs(b.v).max()
    e_scale = np.abs(b.total_energy).max() + np.abs(b.external_work).max()
    for name in ("total_energy", "potential", "kinetic", "external_work"):
        assert np.abs(getattr(a, name) - getattr(b, name)).max() <= e_tol * e_scale, name
    # momenta cancel (a spinning body about a pinned hub has |p| ≪ m |v|): compare on the scale of m |v| ~ E / |v|
    p_scale = np.abs(b.linear_momentum).max() + e_scale / max(np.abs(b.v).max(), 1e-300)
    assert np.abs(a.linear_momentum - b.linear_momentum).max() <= e_tol * p_scale
    assert np.abs(a.angular_momentum - b.angular_momentum).max() <= v_tol * (np.abs(b.angular_momentum).max()
                                                                            + p_scale * np.abs(b.q[:, :2]).max())
    if b.prescribed_force.size:
        assert np.abs(a.prescribed_force - b.prescribed_force).max() <= e_tol * np.abs(b.prescribed_force).max()
    for k in b.probes:
        np.testing.assert_allclose(a.probes[k], b.probes[k], rtol=0, atol=q_tol * np.abs(b.q).max())
    total_a, total_b = a.newton_iterations.sum(), b.newton_iterations.sum()
    # a step decided at the round-off floor may take one iteration more or less on either path (the
    # start from rest); a minority of the recorded steps may do so
    assert abs(total_a - total_b) <= 0.05 * total_b + 0.3 * a.t.size
    # the compiled run conserves energy as exactly as the Python one
    bal = np.abs(a.total_energy - a.total_energy[0] - a.external_work).max()
    assert bal <= 1e-12 * e_scale + 10 * np.abs(b.total_energy - b.total_energy[0] - b.external_work).max()


def assert_loop_measures_are_the_scenes(scene, rel, scheme="energy-momentum"):
    """T, V and the momenta the compiled loop computed for the recorded states equal the scene's at (q, v)
    (under the Newmark schemes a step's record takes them from its acceptance, which computed them)."""
    res = sf.simulate(scene, t_end=0.2, dt=1e-2, record_every=3, scheme=scheme)
    assert res.run_path["python_elements"] == [], res.run_path        # the loop's own measures, no Python
    for k in range(res.t.size):
        q, v = res.q[k], res.v[k]
        assert res.kinetic[k] == pytest.approx(scene.kinetic_energy(q, v), rel=rel)
        assert res.potential[k] == pytest.approx(scene.potential_energy(q), rel=1e-12, abs=1e-15)
        np.testing.assert_allclose(res.linear_momentum[k], scene.linear_momentum(q, v), rtol=rel, atol=1e-13)
        assert res.angular_momentum[k] == pytest.approx(scene.angular_momentum(q, v), rel=rel)


# ------------------------------------------------------------------ command line and examples
#: the folder holding the skfem_flex these tests import (the installed package under ``pytest``): first on the
#: path of every subprocess, so that it runs the same package and finds its kernels in the same cache
PACKAGE_PARENT = ahead.PACKAGE_PARENT
#: this process's environment with PACKAGE_PARENT first on ``PYTHONPATH`` (and keyword settings)
package_env = ahead.package_environment


def command():
    """The installed console script if there is one, else the module."""
    exe = shutil.which("skfem-flex")
    return [exe] if exe else [sys.executable, "-m", "skfem_flex.apps.cli"]


def load_example(name):
    """Import ``examples/NAME.py`` as a module (its module-level computations run; its ``__main__`` part
    does not)."""
    spec = importlib.util.spec_from_file_location(f"{name}_example", ROOT / "examples" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def default_sigint():
    """``preexec_fn`` of a child that a test interrupts: SIGINT back to its default. A job a POSIX shell
    starts in the background (``cmd &``, as some CI runners do) inherits SIGINT ignored, and Python
    then never raises KeyboardInterrupt; a user's terminal gives the default."""
    import signal
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def random_scene_state(scene, rng):
    """A state of ``scene`` near its initial one: q₀ + 0.02 N(0, 1) (Cayley coordinates + 0.3 N more),
    v₀ + N(0, 1)."""
    q0, v0 = scene.initial_state()
    q0 = q0 + 0.02 * rng.normal(size=q0.size)
    for c in scene.cayley_index:
        q0[c] += 0.3 * rng.normal()
    return q0, v0 + rng.normal(size=q0.size)


def warm_compile_cache():
    """Compile every unit the catalogue's scenes need under the three schemes (the kernels most tests run)
    that the cache lacks, on two processes (skfem_flex.compiled.ahead); returns how many were missing."""
    import logging
    import os

    from skfem_flex.compiled import registry
    from skfem_flex.compiled.ahead import compile_units
    from skfem_flex.compiled.pack import packed_scene
    from skfem_flex.schemes.stepper import units

    schemes = (sf.EnergyMomentum(), sf.Trapezoidal(), sf.GeneralizedAlpha())
    todo = []
    scenes = [sf.scenes.CATALOGUE[name]() for name in sorted(sf.scenes.CATALOGUE)]
    scenes.append(sf.scenes.heavy_top(rotation="quaternion"))      # the catalogue's one other body family
    for scene in scenes:
        packed = packed_scene(scene)
        todo += [u for scheme in schemes for u in units(packed, scheme)]
    todo = list(dict.fromkeys(todo))
    todo = [u for u in todo if u.nrt] + [u for u in todo if not u.nrt]      # the largest first
    missing = sum(not registry.is_cached(u) for u in todo)
    level, before = registry.LOGGER.level, os.environ.get("SKFEM_FLEX_COMPILE_PROCESSES")
    registry.LOGGER.setLevel(logging.WARNING)
    os.environ["SKFEM_FLEX_COMPILE_PROCESSES"] = "2"
    try:
        compile_units(todo)
    finally:
        registry.LOGGER.setLevel(level)
        os.environ["SKFEM_FLEX_COMPILE_PROCESSES"] = before if before is not None else "1"
    return missing
