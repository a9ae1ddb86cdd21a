"""The benchmark problems in the established C++ code exudyn: now :mod:`skfem_flex.apps.peer`.

The models (spin-up, flexible pendulum, rigid pendulum) live in the package,
where the work–precision study (``skfem-flex study work-precision``) runs them
beside our schemes; this module keeps the old names for scripts that
``import peer_exudyn``. exudyn is optional (``pip install ".[bench]"``).
"""
from skfem_flex.apps.peer import flexible_pendulum, pendulum, peer_available, spin_up, version

__all__ = ["available", "version", "spin_up", "flexible_pendulum", "pendulum"]


def available():
    """True when exudyn can be imported."""
    return peer_available()


if __name__ == "__main__":
    if not available():
        raise SystemExit('exudyn is not installed: pip install ".[bench]"')
    for label, run in (("spin-up, 8 elements, dt = 1e-3, 30 s", spin_up(8, 1e-3, 30.0)),
                       ("flexible pendulum, 16 elements, dt = 1e-3, 2 s", flexible_pendulum(16, 1e-3, 2.0)),
                       ("rigid pendulum, dt = 1e-2, 10 s", pendulum(1e-2, 10.0))):
        t, probe, seconds = run()
        print(f"exudyn {version()}: {label}: {seconds:.3g} s, {run.stats['steps']} steps, "
              f"{run.stats['newton'] / max(run.stats['steps'], 1):.2f} Newton/step, final probe {probe[-1]}")
