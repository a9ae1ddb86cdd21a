"""Benchmark: our code and exudyn side by side, in one process, alternating, every step recorded on both sides.

With exudyn installed (``pip install ".[bench]"``), the same problems in both codes
(:mod:`skfem_flex.apps.peer`), median of ``--repeat``: spin-up (8 elements, Δt = 1e-3, 30 s), flexible
pendulum (16 elements, Δt = 1e-4 and 1e-3, 2 s), rigid pendulum (Δt = 1e-2, 100 s: 10 000 steps; exudyn's
trapezoidal rule and generalized-α). Each code's error is the
largest distance over the run between its probe and a converged reference: the exact elliptic motion for the
pendulum; for the beams a run refined 4× in space and time (ours for the spin-up, exudyn's for the flexible
pendulum, where ours is slower; the two codes' beams agree to 5e-7 m at equal mesh). Spatial rows
(:mod:`skfem_flex.apps.peer_spatial`: exudyn's Euler-parameter rigid bodies against our director bodies): the
Brüls top (0.2 s, exudyn's generalized-α at Δt = 1e-4), the Simo–Wong top (2 s, exudyn's trapezoidal rule at
1e-3), the rigid chain of 10 and 400 bodies (0.2 s, 1e-3), Bricard's mechanism (2 s, 1e-3), the spatial
slider–crank (5 s, 1e-3; the slider's position), the spatial exact beam (a cantilever under gravity) and the
right-angle frame (30 s, 0.05, exudyn's generalized-α with ρ∞ = 1; the tip), each
against our energy-momentum run at a step 20× smaller, ours at exudyn's step and at the larger step where our
error matches exudyn's. The reduced rotor (its own table): ``rotor_3d``'s whole 1 s spin-up against the same
mesh, M, K and Craig–Bampton basis on exudyn's ``ObjectFFRFreducedOrder`` (:mod:`skfem_flex.apps.peer_reduced`),
CPU µs per step on both sides at 1e-3, 5e-4 and 1e-4 s (the step of exudyn's own performance test of a reduced
rotor), exudyn's generalized-α and trapezoidal rule, errors of the disk centre and of the spin against our run
at 5e-5 s. The rotating beam (its own table): a reduced spatial floating-frame beam with the linear strain
and no rotary inertia on a hub turning at 2 rad/s, 10 s, against exudyn's ``ObjectFFRFreducedOrder`` given the
same nodes, translational mass, reduced stiffness and basis (:mod:`skfem_flex.apps.peer_ffrf_beam`: one reduced
model), CPU µs per step at 1e-2 and 1e-3 s, our trapezoidal rule and energy-momentum against exudyn's trapezoidal
rule and generalized-α, errors of the tip against our trapezoidal run at 2.5e-4 s. The converged references are
computed once and kept in ``OUT/peer_references.npz``.

Run ``python examples/benchmark_peers.py [--repeat 3] [--only TEXT] [--out DIR]`` (``--only``: the problems
whose label holds TEXT; "reduced rotor" for the rotor's table, "rotating beam" for the beam's); writes ``OUT/side_by_side.md`` (default
``examples/output``). ``examples/benchmark.py`` runs the same tables after its own.

Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): every problem for 0.01–0.05 s (of the spatial
chains the 10-body one only; the rotor at its first step only; the rotating beam for 0.05 s, its first row) against references of that length (kept under
their own names in ``peer_references.npz``; exudyn's flexible-pendulum reference on 32 elements instead of 64).
Without exudyn the script says so in one line.
"""
import argparse
import itertools
import os
import statistics
import time
from pathlib import Path

# OpenBLAS keeps a helper thread spinning for a while after each threaded call (the eigensolver that builds
# a reduced body makes one): the spin lands on the CPU time of the next short run, up to twice its own
# work. Threads do not speed up the time loop's small solves (bend_45: the same wall time); with one BLAS
# thread the CPU times are the loop's own work (set OPENBLAS_NUM_THREADS before running to override)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402  (after the BLAS setting, which takes effect when numpy loads)

import skfem_flex as sf

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")


def _max_distance(t, probe, reference):
    """Largest |probe(t) − reference(t)| over the run, m; ``reference`` is callable t -> (n, k) or (n,)."""
    t = np.asarray(t)
    diff = np.asarray(probe).reshape(t.size, -1) - np.asarray(reference(t)).reshape(t.size, -1)
    return float(np.max(np.linalg.norm(diff, axis=1)))


def _spline(t, values):
    from scipy.interpolate import CubicSpline
    return CubicSpline(np.asarray(t), np.asarray(values), axis=0)


def _reference(out, key, compute):
    """A converged reference (t, probe) computed once and kept in OUT/peer_references.npz."""
    path = Path(out) / "peer_references.npz"
    data = dict(np.load(path)) if path.exists() else {}
    if key + "_t" not in data:
        t, probe = compute()
        data[key + "_t"], data[key + "_p"] = np.asarray(t), np.asarray(probe)
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez(path, **data)
    return _spline(data[key + "_t"], data[key + "_p"])


#: simulated seconds of the side-by-side problems: spin-up, flexible pendulum, rigid pendulum
PEER_T = (0.02, 0.02, 0.02) if QUICK else (30.0, 2.0, 100.0)
#: elements of exudyn's flexible-pendulum reference (at 64 its first steps from rest take it thousands of
#: step reductions: a minute even for 0.02 s, too long for quick mode)
PEER_REF_ELEMENTS = 32 if QUICK else 64


def peer_problems(out):
    """[(label, our scene factory, our scheme, dt, t_end, probe, peer run, peer scheme, reference factory)]."""
    from skfem_flex.apps import peer

    spin_t, flex_t, rigid_t = PEER_T
    # quick mode's short references are kept apart from the full ones in the same file
    suffix = "_quick" if QUICK else ""

    def spin_ref():
        r = sf.simulate(sf.scenes.spin_up_beam(omega=4.0, n_elements=32), t_end=spin_t, dt=2.5e-4)
        return r.t, r.probes["tip"]

    def flex_ref():
        t, p, _ = peer.flexible_pendulum(n_elements=PEER_REF_ELEMENTS, dt=2.5e-5, t_end=flex_t)()
        return t, p

    def spin():
        return _reference(out, "spin_up" + suffix, spin_ref)

    def flex():
        return _reference(out, "flexible_pendulum" + suffix, flex_ref)

    def exact():
        from skfem_flex.apps.studies import pendulum_position
        return pendulum_position
    rows = [("spin-up ω = 4, 8 elements", lambda: sf.scenes.spin_up_beam(omega=4.0, n_elements=8),
             "energy-momentum", 1e-3, spin_t, "tip", peer.spin_up(8, 1e-3, spin_t), "generalized-alpha 0.9", spin)]
    for dt in (1e-4, 1e-3):
        rows.append(("flexible pendulum, 16 elements", lambda: sf.scenes.flexible_pendulum(n_elements=16),
                     "energy-momentum", dt, flex_t, "tip", peer.flexible_pendulum(16, dt, flex_t),
                     "generalized-alpha 0.9", flex))
    # 10 000 steps of Δt = 1e-2 s against exudyn's trapezoidal rule and its generalized-α (ρ∞ = 0.9): ours with
    # the same scheme (the same error) and energy-momentum, at exudyn's step and at the larger step where its
    # error matches generalized-α's
    exudyn_pendulum = {s: peer.pendulum(1e-2, rigid_t, scheme=s) for s in ("trapezoidal", "generalized-alpha")}
    label = {"trapezoidal": "trapezoidal, index 2", "generalized-alpha": "generalized-alpha 0.9"}
    for scheme, dt, peer_scheme in (("trapezoidal", 1e-2, "trapezoidal"),
                                    ("generalized-alpha", 1e-2, "generalized-alpha"),
                                    ("energy-momentum", 1e-2, "generalized-alpha"),
                                    ("energy-momentum", 1.25e-2, "generalized-alpha")):
        rows.append(("rigid pendulum", sf.scenes.pendulum, scheme, dt, rigid_t, "position",
                     exudyn_pendulum[peer_scheme], label[peer_scheme] + ", Δt = 0.01", exact))
    return rows + spatial_peer_problems(out, suffix)


#: simulated seconds of the spatial side-by-side problems: Brüls top, Simo–Wong top, chains, Bricard, slider–crank,
#: beam cantilever, right-angle frame
SPATIAL_T = (0.02, 0.05, 0.01, 0.05, 0.05, 0.02, 0.1) if QUICK else (0.2, 2.0, 0.2, 2.0, 5.0, 1.0, 30.0)


def beam_cantilever(n_elements, order=1, interpolation=None):
    """Our side of :func:`skfem_flex.apps.peer_spatial.beam_cantilever`: a :class:`SpatialExactBeam` with the same
    data (:data:`~skfem_flex.apps.peer_spatial.BEAM_CANTILEVER`), welded to the ground at the origin, under
    gravity along −z; probe ``"tip"``; ``interpolation`` of the beam's elements."""
    from skfem_flex.apps.peer_spatial import BEAM_CANTILEVER as c
    from skfem_flex.bodies.probes import PointProbe
    sec = sf.SpatialSection(EA=c["EA"], GA1=c["GA"], GA2=c["GA"], GJ=c["GJ"], EI1=c["EI"], EI2=c["EI"],
                            rhoA=c["rhoA"], rhoI1=c["rhoI"], rhoI2=c["rhoI"])
    beam = sf.SpatialExactBeam.straight(sec, (0.0, 0.0, 0.0), (c["length"], 0.0, 0.0), n_elements=n_elements,
                                        order=order, normal=(0.0, 1.0, 0.0), name="beam", interpolation=interpolation)
    return sf.Scene([beam], constraints=[sf.Weld3D(beam.point(0.0), name="clamp")],
                    forces=[sf.Gravity((0.0, 0.0, -c["g"]))], probes={"tip": PointProbe(beam.point(c["length"]))},
                    name="cantilever_3d")


def spatial_peer_problems(out, suffix):
    """The spatial rows of :func:`peer_problems`: exudyn with its Euler-parameter rigid bodies
    (:mod:`skfem_flex.apps.peer_spatial`) against our director bodies, each against a converged reference
    of ours (energy-momentum at a step 20× smaller); ours at exudyn's step and at the larger step where our
    error matches exudyn's (the two formulations' error constants differ: on these probes, positions of
    points, the directors' is the smaller)."""
    from skfem_flex.apps import peer_spatial

    bruls_t, top_t, chain_t, bricard_t, crank_t, beam_t, frame_t = SPATIAL_T

    def converged(name, factory, dt, t_end, probe):
        def compute():
            r = sf.simulate(factory(), t_end=t_end, dt=dt / 20, scheme="energy-momentum")
            return r.t, r.probes[probe]
        return lambda: _reference(out, name + suffix, compute)

    rows = []
    bruls = converged("bruls_top", lambda: sf.scenes.heavy_top("bruls"), 1e-4, bruls_t, "com")
    for dt in (1e-4, 4e-4):
        rows.append(("Brüls top", lambda: sf.scenes.heavy_top("bruls"), "energy-momentum", dt, bruls_t, "com",
                     peer_spatial.heavy_top("bruls", 1e-4, bruls_t), "generalized-alpha 0.9, Δt = 1e-4", bruls))
    top = converged("simo_wong_top", lambda: sf.scenes.heavy_top("simo-wong"), 1e-3, top_t, "com")
    for dt in (1e-3, 2e-3):
        rows.append(("Simo–Wong top", lambda: sf.scenes.heavy_top("simo-wong"), "energy-momentum", dt, top_t, "com",
                     peer_spatial.heavy_top("simo-wong", 1e-3, top_t, scheme="trapezoidal"),
                     "trapezoidal, index 2, Δt = 1e-3", top))
    # quick mode exercises the code on the short chain only (the long one's reference alone takes seconds)
    # (the long chain and the slider–crank also at exudyn's relative Newton tolerance, 1e-8; the long chain at
    # equal error too: energy-momentum at the step where its error matches, and generalized-α, exudyn's scheme)
    for n, runs in ((10, ((1e-3, "energy-momentum"), (4e-3, "energy-momentum"))),) + (() if QUICK else (
            (400, ((1e-3, "energy-momentum"), (1e-3, ("energy-momentum", 1e-8)), (8e-4, ("energy-momentum", 1e-8)),
                   (1e-3, ("generalized-alpha", 1e-8)))),)):
        chain = converged(f"rigid_chain_{n}", lambda n=n: sf.scenes.rigid_chain(n), 1e-3, chain_t, "tip")
        for dt, scheme in runs:
            rows.append((f"rigid chain, {n} bodies", lambda n=n: sf.scenes.rigid_chain(n), scheme, dt,
                         chain_t, "tip", peer_spatial.rigid_chain(n, 1e-3, chain_t),
                         "generalized-alpha 0.9, Δt = 1e-3", chain))
    brick = converged("bricard", sf.scenes.bricard, 1e-3, bricard_t, "P3")
    for dt in (1e-3, 1.25e-3):
        rows.append(("Bricard", sf.scenes.bricard, "energy-momentum", dt, bricard_t, "P3",
                     peer_spatial.bricard(1e-3, bricard_t), "generalized-alpha 0.9, Δt = 1e-3", brick))
    # the spatial exact beam against exudyn's: the same two-node, constant-strain discretization with rotations
    # interpolated (our default), so at equal mesh and step the two errors agree; our director interpolation
    # makes the same error on this gently bent cantilever at a lower cost per element
    beam_ref = converged("beam_cantilever", lambda: beam_cantilever(16, order=2), 4e-3, beam_t, "tip")
    # (also at exudyn's relative Newton tolerance, 1e-8, against our default 1e-12: the step's error is the
    # same, and our Newton stops after two iterations instead of four)
    for n, dt in ((8, 5e-3), (16, 2e-3)):
        for interpolation in ("rotations", "directors"):
            for scheme in ("energy-momentum", ("energy-momentum", 1e-8)):
                rows.append((f"spatial exact beam, cantilever under gravity, {n} elements, {interpolation}",
                             lambda n=n, i=interpolation: beam_cantilever(n, interpolation=i), scheme, dt,
                             beam_t, "tip", peer_spatial.beam_cantilever(n, dt, beam_t),
                             f"trapezoidal, index 2, Δt = {dt:g}", beam_ref))
    # the right-angle frame: both codes' two-node elements on 10 per leg, the whole 30 s at the catalogue's step
    # (exudyn's generalized-α without numerical damping); the tip against our run at a step 20× smaller
    frame = converged("right_angle_frame", sf.scenes.right_angle_frame, 0.05, frame_t, "tip")
    exudyn_frame = peer_spatial.right_angle_frame(10, 0.05, frame_t)

    def frame_tip():                        # exudyn's probe is (elbow, tip): the tip is compared
        t, p, seconds = exudyn_frame()
        return t, np.asarray(p)[:, 3:], seconds
    for dt in (0.05, 0.1):
        rows.append(("right-angle frame (tip), 10 elements per leg", sf.scenes.right_angle_frame, "energy-momentum",
                     dt, frame_t, "tip", frame_tip, "generalized-alpha 1.0, Δt = 0.05", frame))
    crank = converged("spatial_slider_crank", sf.scenes.spatial_slider_crank, 1e-3, crank_t, "slider")
    exudyn_crank = peer_spatial.spatial_slider_crank(1e-3, crank_t)

    def slider_only():                      # exudyn's probe is (x_C, θ): the slider's position is compared
        t, p, seconds = exudyn_crank()
        return t, np.asarray(p)[:, 0], seconds
    # (also at the step where our error is exudyn's: the errors are of second order, ours 1.33× exudyn's at 1e-3)
    for dt, scheme in ((1e-3, "energy-momentum"), (1e-3, ("energy-momentum", 1e-8)), (8.5e-4, "energy-momentum"),
                       (2e-3, "energy-momentum")):
        rows.append(("spatial slider–crank (slider position)", sf.scenes.spatial_slider_crank, scheme, dt,
                     crank_t, "slider", slider_only, "generalized-alpha 0.9, Δt = 1e-3", crank))
    return rows


#: the reduced rotor's group: its label (``--only`` matches a part of it), simulated seconds (the scene's whole
#: default run: the spin-up from rest reaches the first critical speed, 237 rad/s, near its end) and reference step (s)
REDUCED_ROTOR = "reduced rotor (rotor_3d: Craig–Bampton, 20 elastic coordinates; disk centre)"
REDUCED_ROTOR_T = 0.02 if QUICK else 1.0
REDUCED_ROTOR_REF_DT = 5e-5
#: its rows: (our Δt, exudyn's Δt, exudyn's scheme, ρ∞): equal steps, ours at the step where our error
#: matches that of exudyn's trapezoidal rule, and both at the step of exudyn's own performance test of a reduced
#: rotor (8 modes, two supports, Δt = 1e-4) (quick mode: the first row only)
REDUCED_ROTOR_ROWS = ((1e-3, 1e-3, "generalized-alpha", 0.9), (5e-4, 5e-4, "generalized-alpha", 0.9),
                      (1e-3, 1e-3, "trapezoidal", 1.0), (6.25e-4, 1e-3, "trapezoidal", 1.0),
                      (1e-4, 1e-4, "generalized-alpha", 0.9))[:1 if QUICK else None]


def reduced_rotor_rows(out, repeat=3):
    """The reduced rotor side by side (:func:`skfem_flex.scenes.rotor_3d` against the same mesh, M, K and
    basis on exudyn's ``ObjectFFRFreducedOrder``, :mod:`skfem_flex.apps.peer_reduced`), every step recorded on
    both sides, alternating, median of ``repeat``.

    Rows (our Δt, our µs/step, our Newton it/step, exudyn's Δt, scheme, exudyn's µs/step, its Newton it/step,
    ratio per step, ratio per run, our error (m), exudyn's error (m), our spin error, exudyn's (rad/s)). Time =
    CPU time (:func:`time.process_time`): exudyn's around its solve; ours, that of the run less that of a
    3-step run of the same scene (the set-up both share). Errors: the largest distance over the run of the
    probe ``"disk"`` (and of ``"spin"``) from our energy-momentum run at Δt = 5e-5 s (20× below the largest
    step)."""
    from skfem_flex.apps import peer_reduced

    suffix = "_quick" if QUICK else ""
    t_end, cache = REDUCED_ROTOR_T, {}

    def compute(probe):
        if "ref" not in cache:
            cache["ref"] = sf.simulate(sf.scenes.rotor_3d(), t_end=t_end, dt=REDUCED_ROTOR_REF_DT,
                                       scheme="energy-momentum", record_every=1)
        return cache["ref"].t, cache["ref"].probes[probe]
    disk = _reference(out, "reduced_rotor_disk" + suffix, lambda: compute("disk"))
    spin = _reference(out, "reduced_rotor_spin" + suffix, lambda: compute("spin"))

    def cpu(make):
        start = time.process_time()
        result = make()
        return time.process_time() - start, result
    sf.simulate(sf.scenes.rotor_3d(), t_end=3e-3, dt=1e-3)            # compile or load our kernels
    rows = []
    for dt, peer_dt, scheme, rho in REDUCED_ROTOR_ROWS:
        n, peer_n = int(round(t_end / dt)), int(round(t_end / peer_dt))
        peer_run = peer_reduced.reduced_rotor(dt=peer_dt, t_end=t_end, scheme=scheme, rho_inf=rho)
        ours, theirs = [], []
        for _ in range(repeat):             # alternate, so that both see the same machine load
            scene = sf.scenes.rotor_3d()
            start_up, _ = cpu(lambda: sf.simulate(scene, t_end=3 * dt, dt=dt, scheme="energy-momentum", record_every=1))
            scene = sf.scenes.rotor_3d()
            whole, res = cpu(lambda: sf.simulate(scene, t_end=t_end, dt=dt, scheme="energy-momentum", record_every=1))
            ours.append((whole - start_up) / (n - 3))
            t, p, _ = peer_run()
            theirs.append(peer_run.stats["cpu_seconds"] / peer_run.stats["steps"])
        mine, peer_s = statistics.median(ours), statistics.median(theirs)
        rows.append((dt, 1e6 * mine, float(np.mean(res.newton_iterations[1:])), peer_dt,
                     f"{scheme} {rho:g}" if scheme == "generalized-alpha" else "trapezoidal, index 2", 1e6 * peer_s,
                     peer_run.stats["newton"] / peer_run.stats["steps"], mine / peer_s, mine * n / (peer_s * peer_n),
                     _max_distance(res.t, res.probes["disk"], disk), _max_distance(t, p, disk),
                     _max_distance(res.t, res.probes["spin"], spin), _max_distance(t, peer_run.stats["spin"], spin)))
    return rows


def reduced_rotor_table(rows, repeat):
    from skfem_flex.apps import peer
    lines = [f"{REDUCED_ROTOR}, {REDUCED_ROTOR_T:g} s from rest: ours (energy-momentum, compiled) against exudyn "
             f"{peer.version()}'s ObjectFFRFreducedOrder (C++ path) with the same mesh, M, K, basis, bearings, "
             f"unbalance and torque; CPU time per step, alternating, median of {repeat}, every step recorded on "
             f"both sides; error = largest distance over the run from our energy-momentum run at Δt = "
             f"{REDUCED_ROTOR_REF_DT:g} s (disk centre off the axis, m; spin rate, rad/s).", "",
             "| our Δt (s) | ours (µs/step) | our Newton it/step | exudyn Δt (s) | exudyn scheme | exudyn (µs/step) "
             "| exudyn Newton it/step | ratio ours/exudyn per step | per run | our error (m) | exudyn error (m) "
             "| our spin error (rad/s) | exudyn spin error (rad/s) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    lines += [f"| {dt:g} | {w:.0f} | {it:.2f} | {pdt:g} | {ps} | {pw:.0f} | {pit:.2f} | {r:.2f} | {rr:.2f} | {e:.2e} "
              f"| {pe:.2e} | {se:.2e} | {pse:.2e} |" for dt, w, it, pdt, ps, pw, pit, r, rr, e, pe, se, pse in rows]
    return "\n".join(lines) + "\n"


#: the reduced rotating beam's group (:mod:`skfem_flex.apps.peer_ffrf_beam`): its label (``--only`` matches a part of
#: it), simulated seconds, reference step (s)
FFRF_BEAM = ("rotating beam (reduced floating frame: linear strain, ρI = 0, 8 clamped modes + stretch = 9 elastic "
             "coordinates; tip in the hub frame)")
FFRF_BEAM_T = 0.05 if QUICK else 10.0
FFRF_BEAM_REF_DT = 2.5e-4
#: its rows: (our Δt, our scheme, exudyn's Δt, exudyn's scheme, ρ∞), ours at exudyn's relative Newton tolerance,
#: 1e-8: the same trapezoidal rule at the same step (the same numbers), energy-momentum against generalized-α
#: at the same step and at the step where our error is exudyn's, and both rules at a step 10× smaller
#: (quick mode: the first row only); each for both of our hubs (joints, driven frame)
#: our Newton tolerances (rtol = ctol = etol) per hub: exudyn's 1e-8 with the joints (a tighter etol, 1e-10, buys
#: energy-momentum a second update a step at Δt = 0.01 s and changes no error); 1e-10 for the driven frame, whose
#: free rows are the elastic ones alone: at 1e-8 some trapezoidal steps at Δt = 1e-3 s pass at their start, unupdated,
#: and the tip's error grows thirtyfold; at 1e-10 every step takes its one update, as with the joints
FFRF_BEAM_TOL = {"joints": 1e-8, "driven": 1e-10}
FFRF_BEAM_ROWS = ((1e-2, "trapezoidal", 1e-2, "trapezoidal", 1.0),
                  (1e-2, "energy-momentum", 1e-2, "generalized-alpha", 0.9),
                  (1 / 110, "energy-momentum", 1e-2, "generalized-alpha", 0.9),
                  (1e-3, "trapezoidal", 1e-3, "trapezoidal", 1.0),
                  (1e-3, "energy-momentum", 1e-3, "generalized-alpha", 0.9))[:1 if QUICK else None]


def ffrf_beam_rows(out, repeat=3):
    """The rotating beam side by side (:mod:`skfem_flex.apps.peer_ffrf_beam`: our reduced spatial floating-frame
    beam and exudyn's ``ObjectFFRFreducedOrder`` with the same nodes, translational mass, reduced stiffness and
    basis: one reduced model), every step recorded on both sides, alternating, median of ``repeat``.

    Rows (our Δt, our scheme, our µs/step, with the Python probe, our Newton it/step, exudyn's Δt, scheme, µs/step,
    Newton it/step, ratio per step, ratio per run, our error (m), exudyn's error (m)). Time = CPU time
    (:func:`time.process_time`): exudyn's around its solve; ours, that of the run and of the probe taken from
    the recorded coordinates (one matrix product, :func:`~skfem_flex.apps.peer_ffrf_beam.tip_map`) less that of a
    3-step run of the same (the set-up both share); "with the Python probe": the same with the scene's probe
    called at every recorded step instead. Error: the largest distance over the run of the tip's displacement
    in the hub frame from our trapezoidal run at Δt = 2.5e-4 s (the two codes' trapezoidal runs agree to
    round-off at equal steps, so the reference is either's)."""
    from skfem_flex.apps import peer_ffrf_beam

    suffix = "_quick" if QUICK else ""
    t_end, data = FFRF_BEAM_T, peer_ffrf_beam.beam_data()
    G = peer_ffrf_beam.tip_map(data)
    def tight(hub):
        return sf.NewtonSettings(rtol=FFRF_BEAM_TOL[hub], ctol=FFRF_BEAM_TOL[hub], etol=FFRF_BEAM_TOL[hub])

    def compute():
        r = sf.simulate(peer_ffrf_beam.scene(data, probe=False), t_end=t_end, dt=FFRF_BEAM_REF_DT,
                        scheme="trapezoidal", record_every=1)
        return r.t, r.q[:, 12:] @ G.T
    ref = _reference(out, "ffrf_rotating_beam" + suffix, compute)

    def ours(dt, scheme, t, probe, hub):
        r = sf.simulate(peer_ffrf_beam.scene(data, probe=probe, hub=hub), t_end=t, dt=dt, scheme=scheme,
                        newton=tight(hub), record_every=1)
        return r, (r.probes["tip"] if probe else r.q[:, 12:] @ G.T)

    def cpu(make):
        start = time.process_time()
        result = make()
        return time.process_time() - start, result
    for hub in peer_ffrf_beam.HUBS:
        ours(1e-2, "trapezoidal", 3e-2, False, hub)               # compile or load our kernels
    rows = []
    for hub, (dt, scheme, peer_dt, peer_scheme, rho) in itertools.product(peer_ffrf_beam.HUBS, FFRF_BEAM_ROWS):
        n, peer_n = int(round(t_end / dt)), int(round(t_end / peer_dt))
        peer_run = peer_ffrf_beam.rotating_beam(dt=peer_dt, t_end=t_end, scheme=peer_scheme, rho_inf=rho, data=data)
        mine, mine_probe, theirs = [], [], []
        for _ in range(repeat):             # alternate, so that both see the same machine load
            for probe, into in ((False, mine), (True, mine_probe)):
                start_up, _ = cpu(lambda: ours(dt, scheme, 3 * dt, probe, hub))
                whole, (res, tip) = cpu(lambda: ours(dt, scheme, t_end, probe, hub))
                into.append((whole - start_up) / (n - 3))
            t, p, _ = peer_run()
            theirs.append(peer_run.stats["cpu_seconds"] / peer_run.stats["steps"])
        mine, mine_probe, peer_s = statistics.median(mine), statistics.median(mine_probe), statistics.median(theirs)
        rows.append((dt, f"{scheme}, hub {hub}, Newton tolerances {FFRF_BEAM_TOL[hub]:g}", 1e6 * mine, 1e6 * mine_probe,
                     float(np.mean(res.newton_iterations[1:])), peer_dt,
                     f"{peer_scheme} {rho:g}" if peer_scheme == "generalized-alpha" else "trapezoidal, index 2",
                     1e6 * peer_s, peer_run.stats["newton"] / peer_run.stats["steps"], mine / peer_s,
                     mine * n / (peer_s * peer_n), _max_distance(res.t, tip, ref), _max_distance(t, p, ref)))
    return rows


def ffrf_beam_table(rows, repeat):
    from skfem_flex.apps import peer
    lines = [f"{FFRF_BEAM}, {FFRF_BEAM_T:g} s at Ω = 2 rad/s: ours (compiled) against exudyn {peer.version()}'s "
             f"ObjectFFRFreducedOrder (C++ path) with the same nodes, translational mass, reduced stiffness and "
             f"basis (one reduced model); CPU time per step, alternating, median of {repeat}, every step recorded "
             f"on both sides (ours: the probe from the recorded coordinates; the next column with the scene's "
             f"Python probe called at every step); error = largest distance over the run of the tip's "
             f"displacement from our trapezoidal run at Δt = {FFRF_BEAM_REF_DT:g} s, m. Our hub: \"joints\" a hinge "
             f"and a rate driver (33 Newton unknowns), \"driven\" the frame's motion prescribed (driven_frame: 9 "
             f"unknowns); exudyn's is its reference node held by coordinate constraints (21 unknowns). Our Newton "
             f"tolerances rtol = ctol = etol, as in the scheme column.", "",
             "| our Δt (s) | our scheme | ours (µs/step) | ours with the Python probe (µs/step) | our Newton it/step "
             "| exudyn Δt (s) | exudyn scheme | exudyn (µs/step) | exudyn Newton it/step | ratio ours/exudyn per step "
             "| per run | our error (m) | exudyn error (m) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    lines += [f"| {dt:.4g} | {s} | {w:.0f} | {wp:.0f} | {it:.2f} | {pdt:g} | {ps} | {pw:.0f} | {pit:.2f} | {r:.2f} "
              f"| {rr:.2f} | {e:.2e} | {pe:.2e} |" for dt, s, w, wp, it, pdt, ps, pw, pit, r, rr, e, pe in rows]
    return "\n".join(lines) + "\n"


def peer_rows(out, repeat=3, only=None):
    """Rows (problem, dt, our scheme, our compile and start-up s, ours s, peer scheme, peer s, ratio, our error,
    peer error).

    ``only``: a substring of the problem labels to run (all by default). Our side first runs 3 steps of the
    same scene and scheme (compile or cache load of its kernels), timed apart.
    """
    rows = []
    for label, scene, scheme, dt, t_end, probe, peer_run, peer_scheme, ref in peer_problems(out):
        if only is not None and only not in label:
            continue
        ref = ref()
        # a scheme is its name, or (name, relative Newton tolerance) for a row at exudyn's tolerance
        name, rtol = (scheme, None) if isinstance(scheme, str) else scheme
        newton = None if rtol is None else sf.NewtonSettings(rtol=rtol, ctol=rtol, etol=1e-2 * rtol)
        start = time.perf_counter()
        sf.simulate(scene(), t_end=3 * dt, dt=dt, integrator=name, newton=newton)
        startup = time.perf_counter() - start
        ours, theirs = [], []
        for _ in range(repeat):             # alternate, so that both see the same machine load
            res = sf.simulate(scene(), t_end=t_end, dt=dt, integrator=name, newton=newton, record_every=1)
            ours.append(res.wall_time)
            t, p, seconds = peer_run()
            theirs.append(seconds)
        mine, peer_s = statistics.median(ours), statistics.median(theirs)
        rows.append((label, dt, name if rtol is None else f"{name}, Newton rtol {rtol:g}", startup, mine,
                     peer_scheme, peer_s, mine / peer_s,
                     _max_distance(res.t, res.probes[probe], ref), _max_distance(t, p, ref)))
    return rows


def peer_table(rows, repeat):
    from skfem_flex.apps import peer
    lines = [f"Side by side with exudyn {peer.version()} in this process, alternating, median of {repeat}, "
             f"every step recorded on both sides; error = largest distance (m) over the run from the converged "
             f"reference.", "",
             "| problem | Δt (s) | our scheme | our compile and start-up (s) | ours (s) | exudyn scheme | exudyn (s) "
             "| ratio ours/exudyn | our error (m) | exudyn error (m) |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    lines += [f"| {a} | {dt:g} | {s} | {c:.2f} | {w:.3g} | {ps} | {pw:.3g} | {r:.2f} | {e:.2e} | {pe:.2e} |"
              for a, dt, s, c, w, ps, pw, r, e, pe in rows]
    return "\n".join(lines) + "\n"


def tables(out, repeat=3, only=None):
    """The side-by-side tables as Markdown (``only``: the problems whose label holds this text), or one line
    saying that exudyn is not installed."""
    from skfem_flex.apps.peer import peer_available
    if not peer_available():
        return "exudyn is not installed (pip install \".[bench]\"): no side-by-side table.\n"
    parts = []
    rows = peer_rows(out, repeat, only)
    if rows or only is None:
        parts.append(peer_table(rows, repeat))
    if only is None or only in REDUCED_ROTOR:
        parts.append(reduced_rotor_table(reduced_rotor_rows(out, repeat), repeat))
    if only is None or only in FFRF_BEAM:
        parts.append(ffrf_beam_table(ffrf_beam_rows(out, repeat), repeat))
    return "\n".join(parts)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1 if QUICK else 3)
    ap.add_argument("--only", default=None, help="only the problems whose label holds this text")
    ap.add_argument("--out", default=str(Path(__file__).parent / "output"))
    args = ap.parse_args()
    text = tables(args.out, args.repeat, args.only)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "side_by_side.md").write_text(text)
    print(text)
    print(f"written to {out / 'side_by_side.md'}")
