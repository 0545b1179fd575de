"""Trajectory speed: armkit against scipy, ruckig, toppra and plain NumPy on the same work.

    python benchmarks/trajectory.py            # every case
    python benchmarks/trajectory.py --quick    # fewer repeats, 1e5 samples
    python benchmarks/trajectory.py --profiles --cpu   # case 3 only, in thread CPU time

1. spline construction, 6 joints through 100 via points: cubic against scipy's CubicSpline
   (the same clamped spline), quintic against scipy's make_interp_spline (the same C4 quintic),
   4-5-...-5 against a dense NumPy solve of the same linear system;
2. evaluation of position, velocity, acceleration and jerk at 1e6 sorted times: against scipy
   (four calls, one per derivative) and a vectorised NumPy Horner evaluation;
3. jerk-limited profiles, 6 joints, 1000 random start/goal pairs: the batch call against
   ruckig's ``calculate`` called 1000 times (its own loop over the same pairs, from Python),
   with the largest duration difference; also one call of each, and ruckig's call with its
   inputs set and its phases read back (what ruckig as armkit's single-call backend would cost
   before building armkit's result);
4. retiming a 6-joint path through 10 waypoints within velocity and acceleration limits:
   against toppra on the same spline and the same grid, with both durations.

Every figure is min-median-max over rounds in which armkit and its reference take turns
(benchmarks/common.py); every ratio is reference time / armkit time (above 1: armkit faster),
the ratio of the medians with the range of the per-round ratios. The load average is printed
before and after. With ``--cpu`` case 3 is timed in this thread's CPU time instead of wall
time: on a shared, loaded machine the time the thread waits for a core then stays out, and
single calls of a few microseconds vary less from run to run.
"""

from __future__ import annotations

import argparse
import logging
import time
from functools import partial

import numpy as np
import ruckig
import toppra
import toppra.algorithm
import toppra.constraint
from scipy.interpolate import CubicSpline, make_interp_spline

from armkit.jit import set_mode
from armkit.trajectory import jerk_limited, jerk_limited_profile, retime, spline, waypoint_path
from armkit.trajectory.splines import _System
from common import Spread, interleaved, load, ratio

logging.getLogger("toppra").setLevel(logging.ERROR)


def line(case: str, ours: Spread, name: str, ref: Spread, unit: str = "ms"):
    print(f"  {case:38} {ours.text(unit):>28}   {name:26} {ref.text(unit):>28}   "
          f"{ratio(ref, ours)}")


def pair(ours, reference, rounds: int, number: int = 1) -> tuple[Spread, Spread]:
    times = interleaved({"ours": ours, "reference": reference}, rounds, number)
    return times["ours"], times["reference"]


def per(spread: Spread, count: int) -> Spread:
    return Spread(tuple(t / count for t in spread.times))


def dense_solve(t, q, degrees) -> None:
    """Plain NumPy baseline: the same conditions and least-jerk KKT system, solved densely."""
    system = _System(t, np.asarray(degrees), 2)
    zero = np.zeros(q.shape[1])
    (rows, cols, vals), b, _ = system.conditions(q, {(0, 1): zero, (1, 1): zero, (0, 2): zero,
                                                     (1, 2): zero})
    U, R = int(system.off[-1]), len(b)
    K = np.zeros((U + R, U + R))
    hr, hc, hv = system.jerk_weights()
    K[hr, hc] = hv
    K[U + rows, cols] = vals
    K[cols, U + rows] = vals
    np.linalg.solve(K, np.vstack([np.zeros((U, q.shape[1])), b]))


def numpy_evaluate(tr, t):
    """Plain NumPy baseline: searchsorted, then Horner per derivative on gathered coefficients."""
    i = np.clip(np.searchsorted(tr.breaks, t, side="right") - 1, 0, len(tr.breaks) - 2)
    tau = (t - tr.breaks[i])[:, None]
    c = tr.coefficients[i]                                        # (N, K, n)
    K = c.shape[1]
    out = []
    for r in range(4):
        acc = np.zeros((len(t), c.shape[2]))
        for k in range(K - 1, r - 1, -1):
            factor = np.prod(np.arange(k - r + 1, k + 1)) if r else 1
            acc = acc * tau + factor * c[:, k]
        out.append(acc)
    return out


def splines(rng, repeat: int) -> None:
    print("1. spline construction, 6 joints, 100 via points (101 knots)")
    t = np.r_[0.0, np.cumsum(rng.uniform(0.2, 1.0, 100))]
    q = rng.uniform(-2, 2, (101, 6))
    zero = np.zeros(6)
    cases = [("3-3-...-3 (clamped cubic)", 3, "scipy CubicSpline",
              lambda: CubicSpline(t, q, bc_type="clamped")),
             ("5-5-...-5 (least jerk = C4 quintic)", 5, "scipy make_interp_spline",
              lambda: make_interp_spline(t, q, k=5, bc_type=([(1, zero), (2, zero)],
                                                             [(1, zero), (2, zero)]))),
             ("4-5-...-5 (least jerk)", [4] + [5] * 99, "NumPy dense solve",
              lambda: dense_solve(t, q, [4] + [5] * 99))]
    for case, degrees, name, reference in cases:
        ours, ref = pair(lambda: spline(t, q, degrees), reference, repeat)
        line(case, ours, name, ref)


def evaluation(rng, count: int, repeat: int) -> None:
    print(f"2. evaluation, position to jerk, 6 joints, {count:.0e} sorted samples")
    t = np.r_[0.0, np.cumsum(rng.uniform(0.2, 1.0, 100))]
    q = rng.uniform(-2, 2, (101, 6))
    samples = np.sort(rng.uniform(0, t[-1], count))
    for degree, reference in ((3, CubicSpline(t, q, bc_type="clamped")),
                              (5, make_interp_spline(t, q, k=5, bc_type=(
                                  [(1, np.zeros(6)), (2, np.zeros(6))],
                                  [(1, np.zeros(6)), (2, np.zeros(6))])))):
        tr = spline(t, q, degree)
        s = tr.sample(samples[:1000])
        assert np.allclose(s.qddd, reference(samples[:1000], 3), atol=1e-6)
        assert np.allclose(numpy_evaluate(tr, samples[:1000])[3], s.qddd, atol=1e-9)
        times = interleaved({"ours": lambda: tr.sample(samples),
                             "scipy": lambda: [reference(samples, r) for r in range(4)],
                             "numpy": lambda: numpy_evaluate(tr, samples)}, repeat)
        line(f"degree {degree}: Trajectory.sample", times["ours"], "scipy (4 calls)",
             times["scipy"])
        line("", times["ours"], "NumPy Horner", times["numpy"])


def profiles(rng, pairs: int, repeat: int, cpu: bool = False) -> None:
    clock = "thread CPU time" if cpu else "wall time"
    print(f"3. jerk-limited profiles, 6 joints, {pairs} random start/goal pairs, time sync "
          f"({clock})")
    timed = partial(interleaved, clock=time.thread_time if cpu else time.perf_counter)
    q0, qf = rng.uniform(-3, 3, (pairs, 6)), rng.uniform(-3, 3, (pairs, 6))
    vmax, amax, jmax = rng.uniform(0.5, 2, 6), rng.uniform(1, 4, 6), rng.uniform(2, 20, 6)
    otg, inp, out = ruckig.Ruckig(6), ruckig.InputParameter(6), ruckig.Trajectory(6)
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = (list(x) for x in (vmax, amax, jmax))
    starts, goals = q0.tolist(), qf.tolist()        # lists: ruckig's fastest input from Python

    def reference():
        durations = [0.0] * pairs
        for i in range(pairs):
            inp.current_position, inp.target_position = starts[i], goals[i]
            otg.calculate(inp, out)
            durations[i] = out.duration
        return np.array(durations)

    ours = jerk_limited_profile(q0, qf, vmax, amax, jmax).duration
    worst = np.abs(ours / reference() - 1).max()
    times = timed({"ours": lambda: jerk_limited_profile(q0, qf, vmax, amax, jmax),
                   "reference": reference}, repeat)
    batch, loop = times["ours"], times["reference"]
    line("batch jerk_limited_profile, per pair", per(batch, pairs), "ruckig.calculate, per pair",
         per(loop, pairs), "us")
    inp.current_position, inp.target_position = starts[0], goals[0]
    a, b = q0[0], qf[0]
    def ruckig_phases():
        """What using ruckig for one call would cost: its inputs set, its calculation, and its
        seven phases per joint read back (durations and jerks), before any armkit type."""
        inp.current_position, inp.target_position = starts[0], goals[0]
        otg.calculate(inp, out)
        return [(p.t, p.j) for p in out.profiles[0]]

    times = timed({"profile": lambda: jerk_limited_profile(a, b, vmax, amax, jmax),
                   "trajectory": lambda: jerk_limited(a, b, vmax, amax, jmax),
                   "ruckig": lambda: otg.calculate(inp, out),
                   "ruckig phases": ruckig_phases}, repeat, number=1000)
    line("one jerk_limited_profile call", times["profile"], "one ruckig.calculate",
         times["ruckig"], "us")
    line("one jerk_limited (a Trajectory)", times["trajectory"], "one ruckig.calculate",
         times["ruckig"], "us")
    line("one jerk_limited_profile call", times["profile"], "ruckig, inputs + phases read",
         times["ruckig phases"], "us")
    print(f"  largest relative duration difference to ruckig: {worst:.1e}")


def retiming(rng, repeat: int) -> None:
    print("4. retiming, 6 joints, path through 10 waypoints, grid of 1000 intervals")
    waypoints = rng.uniform(-1.5, 1.5, (10, 6))
    vmax, amax = rng.uniform(0.5, 2.0, 6), rng.uniform(1.0, 4.0, 6)
    path = waypoint_path(waypoints)
    reference_path = toppra.SplineInterpolator(path.knots, waypoints, bc_type="natural")
    grid = np.union1d(np.linspace(0, path.end, 1001), path.knots)
    constraints = [toppra.constraint.JointVelocityConstraint(np.c_[-vmax, vmax]),
                   toppra.constraint.JointAccelerationConstraint(np.c_[-amax, amax])]

    def reference():
        algorithm = toppra.algorithm.TOPPRA(constraints, reference_path, gridpoints=grid,
                                            parametrizer="ParametrizeConstAccel")
        return algorithm.compute_trajectory()

    ours_tr, theirs_tr = retime(path, vmax, amax).trajectory, reference()
    ours, ref = pair(lambda: retime(path, vmax, amax), reference, repeat)
    line("retime (TOPP-RA, numba)", ours, "toppra TOPPRA", ref)
    dense = ours_tr.sample(np.linspace(0, ours_tr.end, 200_001))
    ts = np.linspace(0, theirs_tr.duration, 200_001)
    print(f"  duration: armkit {ours_tr.duration:.5f} s, toppra {theirs_tr.duration:.5f} s "
          f"({ours_tr.duration / theirs_tr.duration - 1:+.3%})\n  largest |v|/vmax, |a|/amax on "
          f"2e5 samples: armkit {np.max(np.abs(dense.qd) / vmax):.7f}, "
          f"{np.max(np.abs(dense.qdd) / amax):.7f}; toppra "
          f"{np.max(np.abs(theirs_tr(ts, 1)) / vmax):.7f}, "
          f"{np.max(np.abs(theirs_tr(ts, 2)) / amax):.7f}")


def main() -> None:
    set_mode("compiled")        # compiled speed from the first call (armkit.jit)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats, 1e5 samples")
    parser.add_argument("--profiles", action="store_true", help="only the profiles (case 3)")
    parser.add_argument("--cpu", action="store_true",
                        help="time case 3 in thread CPU time instead of wall time")
    args = parser.parse_args()
    repeat = 3 if args.quick else 7
    rng = np.random.default_rng(0)
    spline([0, 1], [[0.0], [1.0]], 5).sample(np.linspace(0, 1, 10_000))     # compile kernels
    retime([[0.0, 0.0], [1.0, 1.0]], 1.0, 1.0, grid=10)
    jerk_limited_profile(np.zeros(2), np.ones(2), 1.0, 1.0, 1.0)
    print(load())
    print(f"  {'':38} {'armkit':>28}   {'reference':26} {'':>28}   ratio [per round]")
    if args.profiles:
        profiles(rng, 1000, repeat, args.cpu)
        print(load())
        return
    splines(rng, repeat)
    evaluation(rng, 100_000 if args.quick else 1_000_000, repeat)
    profiles(rng, 1000, repeat, args.cpu)
    retiming(rng, repeat)
    print(load())


if __name__ == "__main__":
    main()
