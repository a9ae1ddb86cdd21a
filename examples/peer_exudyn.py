"""The benchmark problems in the established C++ code exudyn: now :mod:`skfem_flex.apps.peer`.

The models (spin-up, flexible pendulum, rigid pendulum) live in the package,
where the work–precision study (``skfem-flex study work-precision``) runs them
beside our schemes; this module keeps the old names for scripts that
``import peer_exudyn``. exudyn is optional (``pip install ".[bench]"``).

Run ``python examples/peer_exudyn.py``: each problem once in exudyn (spin-up 30 s, flexible pendulum 2 s,
rigid pendulum 10 s). Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): 0.05 s each.
"""
import os

from skfem_flex.apps.peer import flexible_pendulum, pendulum, peer_available, spin_up, version

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")

__all__ = ["available", "version", "spin_up", "flexible_pendulum", "pendulum"]


def available():
    """True when exudyn can be imported."""
    return peer_available()


if __name__ == "__main__":
    if not available():
        raise SystemExit('exudyn is not installed: pip install ".[bench]"')
    spin_t, flex_t, rigid_t = (0.05, 0.05, 0.05) if QUICK else (30.0, 2.0, 10.0)
    for label, run in ((f"spin-up, 8 elements, dt = 1e-3, {spin_t:g} s", spin_up(8, 1e-3, spin_t)),
                       (f"flexible pendulum, 16 elements, dt = 1e-3, {flex_t:g} s",
                        flexible_pendulum(16, 1e-3, flex_t)),
                       (f"rigid pendulum, dt = 1e-2, {rigid_t:g} s", pendulum(1e-2, rigid_t))):
        t, probe, seconds = run()
        print(f"exudyn {version()}: {label}: {seconds:.3g} s, {run.stats['steps']} steps, "
              f"{run.stats['newton'] / max(run.stats['steps'], 1):.2f} Newton/step, final probe {probe[-1]}")
