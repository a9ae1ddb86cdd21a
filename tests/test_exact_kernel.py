"""Compiled ExactBeam kernels (skfem_flex.bodies.exact.kernel) against the numpy methods of ExactBeam."""
import time

import numba
import numpy as np
import pytest
import scipy.sparse as sps

import skfem_flex as sf
from skfem_flex.bodies.exact import kernel as ek
from skfem_flex.bodies.exact import strain as exact_strain
from skfem_flex.bodies.exact.body import ExactBeam
from skfem_flex.bodies.exact.strain import ElementInversionError
from skfem_flex.errors import ConvergenceError
from skfem_flex.numerics.rotations import MAX_INCREMENT

from helpers import FLYING_BEAM_SECTION as SECTION, dense

TOL = 1e-12


def _sinc_accurate(z):
    """sin z / z for complex z, by its Taylor series for |z| < 1e-2: rotations.sinc (sin z / z) loses the
    imaginary part there (Im = b (a cos a − sin a)/a² for z = a + ib cancels), so the numpy complex-step
    tangent of ExactBeam is off by ~1e-11 relative for increments |Δψ| ~ 1e-9 (measured; harmless to Newton)."""
    z = np.asarray(z, dtype=complex)
    small = np.abs(z) < 1e-2
    zs = np.where(small, 1.0, z)
    z2 = z * z
    return np.where(small, 1.0 - z2 / 6.0 + z2 * z2 / 120.0 - z2 ** 3 / 5040.0, np.sin(zs) / zs)


def _divided_difference_accurate(x, y):
    x, y = np.asarray(x), np.asarray(y)
    return _sinc_accurate(0.5 * (x - y)) / (np.cos(0.5 * x) * np.cos(0.5 * y))


def _ratio_accurate(d):
    h = 0.5 * np.asarray(d)
    return np.cos(h) / _sinc_accurate(h)


def kernel_matrix(kd, data):
    return sps.csr_matrix((data, kd.pat_idx, kd.pat_ptr), shape=(kd.n, kd.n)).toarray()


def arc_state(body, rng, kappa=0.0, turn=0.0, shift=(0.0, 0.0), pos_noise=0.02, psi_noise=0.05):
    """A circular arc of curvature ``kappa`` (1/m), turned by ``turn`` about the beam's start and shifted,
    with random nodal perturbations (positions relative to the element length, angles in rad)."""
    s = body.s_nodes - body.s_min
    a = body.angle + turn
    phi = a + kappa * s
    if kappa == 0.0:
        r = np.outer(s, [np.cos(a), np.sin(a)])
    else:
        r = np.column_stack([(np.sin(phi) - np.sin(a)) / kappa, (np.cos(a) - np.cos(phi)) / kappa])
    q = body.coordinates_from(body.start + np.asarray(shift) + r, phi)
    h = body.length / body.n_elements
    nd = body.node_dofs
    q[nd[:, 0]] += pos_noise * h * rng.standard_normal(len(nd))
    q[nd[:, 1]] += pos_noise * h * rng.standard_normal(len(nd))
    q[nd[:, 2]] += psi_noise * rng.standard_normal(len(nd))
    return q


def step_pairs(body, rng):
    """(label, q0, q1): large, moderate, tiny and zero rotation increments from curved states."""
    L = body.length
    pairs = []
    for k0, k1, turn in ((0.0, 0.5 / L, 0.3), (1.5 / L, 1.0 / L, 2.5), (-2.0 / L, -2.1 / L, -2.5), (0.7 / L, 0.2 / L, 1.0)):
        q0 = arc_state(body, rng, k0, turn=0.4, shift=(0.3, -0.2))
        q1 = arc_state(body, rng, k1, turn=0.4 + turn, shift=(0.5, 0.1), psi_noise=0.02)
        pairs.append((f"turn {turn}", q0, q1))
    q0 = arc_state(body, rng, 1.0 / L)
    pairs.append(("tiny", q0, q0 + 1e-9 * rng.standard_normal(body.n_dofs)))
    pairs.append(("zero", q0, q0.copy()))
    q1 = q0 + 1e-3 * body.length * rng.standard_normal(body.n_dofs)
    q1[body.node_dofs[:, 2]] = q0[body.node_dofs[:, 2]]                # Δψ exactly 0, positions move
    pairs.append(("zero turn", q0, q1))
    q1 = q0.copy()
    q1[body.node_dofs[:, 2]] += 1e-9 * rng.standard_normal(len(body.node_dofs))
    pairs.append(("tiny turn", q0, q1))
    return pairs


BODIES = {
    "P1": lambda: ExactBeam.from_points(SECTION, (6.0, 0.0), (0.0, 8.0), n_elements=5, order=1),
    "P2": lambda: ExactBeam.from_points(SECTION, (6.0, 0.0), (0.0, 8.0), n_elements=4, order=2),
    "pendulum": lambda: sf.scenes.get("very_flexible_pendulum")().bodies[0],
    "flying": lambda: sf.scenes.get("flying_beam")().bodies[0],
    "flying_P2": lambda: sf.scenes.get("flying_beam")(order=2, n_elements=6).bodies[0],
    "sparse": lambda: ExactBeam.from_points(SECTION, (0.0, 0.0), (3.0, 4.0), n_elements=140, order=1),
}


@pytest.mark.parametrize("name", list(BODIES))
def test_kernel_matches_numpy_methods(name, monkeypatch):
    body = BODIES[name]()
    rng = np.random.default_rng(7)
    kd = ek.pack(body)
    if name == "sparse":
        assert not body.dense
    nnz = kd.pat_idx.size
    g, data, floor = np.empty(body.n_dofs), np.empty(nnz), np.empty(body.n_dofs)
    for label, q0, q1 in step_pairs(body, rng):
        where = (name, label)
        # energy
        for q in (q0, q1):
            v = body.potential_energy(q)
            assert abs(ek.potential_energy(kd, q) - v) <= TOL * v, where
            assert ek.state_status(kd, q) == ek.OK
        # discrete gradient, tangent and floor
        assert ek.potential_discrete_gradient(kd, q0, q1, g, data, floor) == ek.OK, where
        g_py, k_py = body.potential_discrete_gradient(q0, q1)
        k_py = dense(k_py)
        floor_py = np.abs(k_py) @ (np.abs(q0) + np.abs(q1))
        g_scale = max(np.abs(g_py).max(), floor_py.max())
        assert np.abs(g - g_py).max() <= TOL * g_scale, where
        k = kernel_matrix(kd, data)
        k_err = np.abs(k - k_py).max() / np.abs(k_py).max()
        if label.startswith("tiny"):            # the plain numpy tangent is off there (see _sinc_accurate)
            assert k_err <= 1e-5, where
            with monkeypatch.context() as mp:
                mp.setattr(exact_strain, "cayley_divided_difference", _divided_difference_accurate)
                mp.setattr(exact_strain, "cayley_ratio", _ratio_accurate)
                k_py = dense(body.potential_discrete_gradient(q0, q1)[1])
            k_err = np.abs(k - k_py).max() / np.abs(k_py).max()
        assert k_err <= TOL, where
        floor_py = np.abs(k_py) @ (np.abs(q0) + np.abs(q1))
        assert np.abs(floor - floor_py).max() <= TOL * floor_py.max(), where
        # exactness: g·Δq = V(q1) − V(q0) to round-off
        dq = q1 - q0
        jump = ek.potential_energy(kd, q1) - ek.potential_energy(kd, q0)
        v_scale = ek.potential_energy(kd, q0) + ek.potential_energy(kd, q1) + np.abs(g) @ np.abs(dq)
        assert abs(g @ dq - jump) <= 1e-13 * v_scale, where
        # the allocating form gives the same
        st, g2, d2, f2 = ek.discrete_gradient_terms(kd, q0, q1)
        assert st == ek.OK and np.array_equal(g2, g) and np.array_equal(d2, data) and np.array_equal(f2, floor)
    # a vanishing step gives the gradient (and the Hessian as the tangent's symmetric limit)
    q0 = arc_state(body, rng, 1.0 / body.length)
    assert ek.potential_discrete_gradient(kd, q0, q0, g, data, floor) == ek.OK
    grad = body.potential_gradient(q0)
    assert np.abs(g - grad).max() <= TOL * max(np.abs(grad).max(), floor.max())
    hess = dense(body.potential_hessian(q0))
    assert np.abs(2.0 * kernel_matrix(kd, data) - hess).max() <= 1e-10 * np.abs(hess).max()


def test_compiled_strain_data_is_packed_once():
    body = sf.scenes.get("very_flexible_pendulum")().bodies[0]
    kd = body.compiled_strain_data()
    assert isinstance(kd, ek.ExactKernelData) and kd is body.compiled_strain_data()
    assert kd.n == body.n_dofs == 51 and kd.ed.shape == (16, 6) and kd.N.shape == (16, 1, 2)
    assert (kd.EA, kd.kGA, kd.EI) == (body.EA, body.kGA, body.EI)
    assert kd.map_el.shape == (16, 6, 6) and kd.map_el.max() < kd.pat_idx.size
    # mid-point rates: the same kernels (they do not depend on the rate); not floating-frame data
    mid = ExactBeam.from_points(SECTION, (0.0, 0.0), (1.0, 0.0), n_elements=3, rotation_rate="mid-point")
    assert isinstance(mid.compiled_strain_data(), ek.ExactKernelData)
    assert not hasattr(mid, "compiled_kernel_data")
    assert ek.pack(mid).n == mid.n_dofs


def test_failures_are_flagged_not_raised():
    for order in (1, 2):
        body = ExactBeam.from_points(SECTION, (6.0, 0.0), (0.0, 8.0), n_elements=4, order=order)
        kd = ek.pack(body)
        rng = np.random.default_rng(3)
        q0 = arc_state(body, rng, 0.1, pos_noise=0.0, psi_noise=0.0)
        g, data, floor = np.empty(body.n_dofs), np.empty(kd.pat_idx.size), np.empty(body.n_dofs)
        nd = body.node_dofs
        # rigid turns: just below MAX_INCREMENT is fine, MAX_INCREMENT, π and more are not
        for turn, status in ((MAX_INCREMENT - 1e-6, ek.OK), (-(MAX_INCREMENT - 1e-6), ek.OK), (MAX_INCREMENT, ek.TURN),
                             (np.pi, ek.TURN), (-np.pi, ek.TURN), (4.0, ek.TURN)):
            q1 = arc_state(body, rng, 0.1, turn=turn, pos_noise=0.0, psi_noise=0.0)
            assert ek.potential_discrete_gradient(kd, q0, q1, g, data, floor) == status, turn
            if status == ek.TURN:
                with pytest.raises(ConvergenceError):
                    body.potential_discrete_gradient(q0, q1)
            else:
                g_py = body.potential_discrete_gradient(q0, q1)[0]
                assert np.abs(g - g_py).max() <= TOL * max(np.abs(g_py).max(), floor.max())
        # one node alone turning by π
        q1 = q0.copy()
        q1[nd[2, 2]] += np.pi
        assert ek.potential_discrete_gradient(kd, q0, q1, g, data, floor) == ek.TURN
        # a folded element in q1 or in q0 (the last node pulled back behind its neighbour)
        q1 = q0.copy()
        d = body.nodal_positions(q0)[-2] - body.nodal_positions(q0)[-1]
        q1[nd[-1, 0]] += 3.0 * d[0]
        q1[nd[-1, 1]] += 3.0 * d[1]
        assert ek.state_status(kd, q1) == ek.FOLDED
        assert ek.potential_discrete_gradient(kd, q0, q1, g, data, floor) == ek.FOLDED
        assert ek.potential_discrete_gradient(kd, q1, q0, g, data, floor) == ek.FOLDED
        for a, b in ((q0, q1), (q1, q0)):
            with pytest.raises(ElementInversionError):
                body.potential_discrete_gradient(a, b)
        # not finite: positions fold (NaN stretch), angles do not turn (NaN increment)
        q1 = q0.copy()
        q1[nd[1, 0]] = np.nan
        assert ek.potential_discrete_gradient(kd, q0, q1, g, data, floor) == ek.FOLDED
        q1 = q0.copy()
        q1[nd[1, 2]] = np.inf
        assert ek.potential_discrete_gradient(kd, q0, q1, g, data, floor) == ek.TURN
        assert ek.state_status(kd, q0) == ek.OK


@numba.njit
def _timing_loop(kd, q0, q1, g, data, floor, m):
    s = 0
    for _ in range(m):
        q1[0] += 1e-15
        s += ek.potential_discrete_gradient(kd, q0, q1, g, data, floor)
    return s


def test_time_per_call_of_the_pendulum_beam():
    body = sf.scenes.get("very_flexible_pendulum")().bodies[0]
    kd = body.compiled_strain_data()
    rng = np.random.default_rng(0)
    q0 = arc_state(body, rng, 1.0)
    q1 = arc_state(body, rng, 1.2, turn=0.1)
    g, data, floor = np.empty(kd.n), np.empty(kd.pat_idx.size), np.empty(kd.n)
    _timing_loop(kd, q0, q1, g, data, floor, 1)
    m, best = 20000, np.inf
    for _ in range(3):
        t = time.perf_counter()
        assert _timing_loop(kd, q0, q1, g, data, floor, m) == 0
        best = min(best, (time.perf_counter() - t) / m)
    print(f"\nExactBeam discrete gradient + tangent + floor, very_flexible_pendulum (51 coordinates): "
          f"{best * 1e6:.2f} us per call")
    assert best < 100e-6                    # measured ≈ 5 us; a loose bound (shared machines)
