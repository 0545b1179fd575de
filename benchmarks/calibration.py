"""Calibration: hand-eye accuracy beside OpenCV's five methods, refusals of degenerate data, and
kinematic calibration accuracy and time beside scipy's least_squares with a finite-difference
Jacobian, all measured in the same run.

    python benchmarks/calibration.py            # 100 hand-eye trials per cell
    python benchmarks/calibration.py --quick    # 20 trials per cell

Hand-eye (eye-in-hand): X is drawn at random (rotation ~ N(0, 1) rad per axis, translation
~ 0.1 m), the target 0.8 m out; each trial draws N gripper poses (rotations of ~0.5 rad, positions
within ~0.2 m) and the camera poses that match, then right-multiplies each camera pose by noise
(rotation sigma_r per axis, translation sigma_t per axis). Errors are those of X against the
truth: rotation angle (deg) and translation distance (mm); median and p95 over the trials.
OpenCV's calibrateHandEye (4.x) runs on the very same arrays.

Degenerate sets (20 seeds each): rotations about one axis, within 0.006 deg of one axis, pure
translations, a repeated pose, and the robot poses inverted (base-to-gripper given as
gripper-to-base). A "silent answer" is a success without a reason.

Kinematic calibration: a true arm is the nominal table with every parameter moved by
realistic amounts (the table's lengths ~N(0, 0.5 mm), its twists and joint offsets ~N(0, 0.2
deg), the base's and tool's translations ~N(0, 1 mm) and rotations ~N(0, 0.5 deg); in one row
only the parameters identifiable at nominal); tool positions are measured with 0.05 mm of
noise per axis; the hold-out set is 300 other configurations, measured without noise.
water_supply with 10 and 30 random measurements, and 10 chosen by select_poses from a pool of
500 (also over 40 true arms, random against D-optimal choices); a UR10-like 6R arm (standard
DH) with 700 measurements, also over 20 true arms beside what the noise alone allows (the
hold-out error of a correctly specified linear least-squares fit of the same noise). The
reference fits the same parameters as armkit with scipy.optimize.least_squares (trf, 2-point
finite differences: the generic way).

pybotics pins numpy < 2, so it runs in an interpreter of its own: with
ARMKIT_PYBOTICS_PYTHON=/path/to/python (of an environment where pybotics is installed),
benchmarks/pybotics_fit.py fits the UR10-like data set there, in a subprocess, and its
hold-out error and time are printed beside armkit's:

    python3.11 -m venv /work/venv-pybotics && /work/venv-pybotics/bin/pip install pybotics
    ARMKIT_PYBOTICS_PYTHON=/work/venv-pybotics/bin/python python benchmarks/calibration.py
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np
from scipy.optimize import least_squares

import armkit
from armkit.jit import set_mode
from armkit.calibration.handeye import handeye
from armkit.calibration.identify import (calibrate, evaluate, identifiability,
                                         identified_robot, parametric_model, select_poses)
from armkit.model import DHRow, DHTable, Limits, Robot, chain_from_dh
from armkit.spatial import exp_so3, invert, rotation_angle

CV = {"tsai": cv2.CALIB_HAND_EYE_TSAI, "park": cv2.CALIB_HAND_EYE_PARK,
      "horaud": cv2.CALIB_HAND_EYE_HORAUD, "andreff": cv2.CALIB_HAND_EYE_ANDREFF,
      "daniilidis": cv2.CALIB_HAND_EYE_DANIILIDIS}
NOISE = ((0.05, 0.25), (0.2, 1.0), (0.5, 2.5))        # (deg, mm) per axis
SIZES = (5, 10, 20)


def pose(rotvec, p):
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = exp_so3(rotvec), p
    return T


def handeye_set(n, rng, noise_deg=0.0, noise_mm=0.0, axis=None):
    X = pose(rng.normal(size=3), rng.normal(size=3) * 0.1)
    W = pose(rng.normal(size=3), [0.8, 0.1, 0.0])
    G, C = [], []
    for _ in range(n):
        rv = rng.normal(size=3) * 0.5 if axis is None else np.asarray(axis) * rng.normal() * 0.8
        Gi = pose(rv, rng.normal(size=3) * 0.2 + [0.5, 0.0, 0.5])
        noise = pose(rng.normal(size=3) * np.deg2rad(noise_deg),
                     rng.normal(size=3) * noise_mm / 1000)
        G.append(Gi)
        C.append(invert(Gi @ X) @ W @ noise)
    return np.array(G), np.array(C), X


def opencv(G, C, method):
    R, t = cv2.calibrateHandEye(G[:, :3, :3], G[:, :3, 3], C[:, :3, :3], C[:, :3, 3],
                                method=CV[method])
    X = np.eye(4)
    X[:3, :3], X[:3, 3] = R, np.ravel(t)
    return X


def x_error(Xe, X):
    if not np.all(np.isfinite(Xe)):
        return np.inf, np.inf
    return (float(np.rad2deg(rotation_angle(Xe[:3, :3].T @ X[:3, :3]))),
            float(np.linalg.norm(Xe[:3, 3] - X[:3, 3]) * 1000))


def timings(f, rounds=7, repeat=5):
    """min, median, max over rounds of the mean time of `repeat` calls (s)."""
    t = []
    for _ in range(rounds):
        start = time.perf_counter()
        for _ in range(repeat):
            f()
        t.append((time.perf_counter() - start) / repeat)
    return min(t), float(np.median(t)), max(t)


def fmt_t(t):
    return " / ".join(f"{v * 1e3:.2f}" for v in t) + " ms"


def handeye_accuracy(trials):
    print(f"\n## Hand-eye accuracy: error of X, median (p95) over {trials} trials")
    print("| noise (deg, mm) | N | armkit joint: rot deg | trans mm | best OpenCV (method): rot "
          "deg | trans mm | joint / best OpenCV (rot, trans) |")
    print("|---|---|---|---|---|---|---|")
    worst_ratio = [0.0, 0.0]
    for noise_deg, noise_mm in NOISE:
        for n in SIZES:
            rng = np.random.default_rng([n, int(noise_mm * 100)])
            ours, theirs, refused = [], {m: [] for m in CV}, 0
            for _ in range(trials):
                G, C, X = handeye_set(n, rng, noise_deg, noise_mm)
                result = handeye(G, C)
                if not result.success:
                    refused += 1
                    continue
                ours.append(x_error(result.X, X))
                for m in CV:
                    theirs[m].append(x_error(opencv(G, C, m), X))
            ours = np.array(ours)
            med = np.median(ours, axis=0)
            p95 = np.percentile(ours, 95, axis=0)
            stats = {m: (np.median(v, axis=0), np.percentile(v, 95, axis=0))
                     for m, v in theirs.items()}
            best_r = min(stats, key=lambda m: stats[m][0][0])
            best_t = min(stats, key=lambda m: stats[m][0][1])
            ratio = med[0] / stats[best_r][0][0], med[1] / stats[best_t][0][1]
            worst_ratio = [max(worst_ratio[0], ratio[0]), max(worst_ratio[1], ratio[1])]
            note = f" ({refused} refused)" if refused else ""
            print(f"| {noise_deg}, {noise_mm} | {n}{note} | {med[0]:.4f} ({p95[0]:.4f}) | "
                  f"{med[1]:.3f} ({p95[1]:.3f}) | {stats[best_r][0][0]:.4f} "
                  f"({stats[best_r][1][0]:.4f}) {best_r} | {stats[best_t][0][1]:.3f} "
                  f"({stats[best_t][1][1]:.3f}) {best_t} | {ratio[0]:.2f}, {ratio[1]:.2f} |")
    print(f"\nworst ratio of joint refinement to the best OpenCV method: rotation "
          f"{worst_ratio[0]:.2f}, translation {worst_ratio[1]:.2f} (target <= 0.70)")
    rng = np.random.default_rng(1)
    G, C, _ = handeye_set(10, rng, 0.2, 1.0)
    print("\ntime per solve, N = 10 (min / median / max over 7 rounds):")
    ref = timings(lambda: opencv(G, C, "tsai"))
    for method in ("tsai", "park", "horaud", "pairs", "joint"):
        t = timings(lambda m=method: handeye(G, C, method=m))
        print(f"  armkit {method:<7} {fmt_t(t)}   (x{t[1] / ref[1]:.1f} OpenCV tsai's "
              f"{ref[1] * 1e3:.2f} ms)")


def degenerate(seeds=20):
    print(f"\n## Degenerate hand-eye data, {seeds} sets each")
    print("| data | armkit: refused (reason) | armkit silent answers | OpenCV tsai: returns an "
          "X | OpenCV tsai: median error of that X (deg, mm) |")
    print("|---|---|---|---|---|")
    cases = {}

    def one_axis(rng):
        return handeye_set(10, rng, 0.01, 0.05, axis=[0, 0, 1])

    def near_one_axis(rng):
        G, C, X = handeye_set(10, rng, axis=[0, 0, 1])
        wobble = np.array([pose([1e-4 * np.sin(k), 1e-4 * np.cos(k), 0], [0, 0, 0])
                           for k in range(10)])
        return G @ wobble, C, X

    def no_rotation(rng):
        X, W = pose(rng.normal(size=3), [0.05, 0, 0.1]), pose(rng.normal(size=3), [1, 0, 0])
        R = pose(rng.normal(size=3), [0, 0, 0])
        G = np.array([R @ pose([0, 0, 0], rng.normal(size=3) * 0.2) for _ in range(10)])
        return G, invert(G @ X) @ W, X

    def repeated(rng):
        G, C, X = handeye_set(9, rng, 0.1, 0.5)
        return np.concatenate([G, G[:1]]), np.concatenate([C, C[:1]]), X

    def inverted(rng):
        G, C, X = handeye_set(10, rng, 0.1, 0.5)
        return invert(G), C, X

    cases = {"one axis": one_axis, "within 0.006 deg of one axis": near_one_axis,
             "pure translations": no_rotation, "a repeated pose": repeated,
             "robot poses inverted": inverted}
    for name, make in cases.items():
        rng = np.random.default_rng(7)
        refused, silent, answers, errs, reason = 0, 0, 0, [], ""
        for _ in range(seeds):
            G, C, X = make(rng)
            result = handeye(G, C)
            if result.success:
                silent += 1
            else:
                refused += 1
                reason = result.reason.split(":")[0]
            Xc = opencv(G, C, "tsai")
            answers += bool(np.all(np.isfinite(Xc)))
            errs.append(x_error(Xc, X))
        med = np.median(np.array(errs), axis=0)
        print(f"| {name} | {refused}/{seeds} ({reason}) | {silent} | {answers}/{seeds} | "
              f"{med[0]:.3g}, {med[1]:.3g} |")
    print("\nOpenCV writes 'Not enough informative motions' to stderr for pure translations, and "
          "returns an X all the same; on the other sets it says nothing.")


# --- kinematic calibration -----------------------------------------------------------------------

def ur10_like() -> Robot:
    """A UR10-like 6R arm (standard DH, m/rad)."""
    d = (0.1273, 0.0, 0.0, 0.163941, 0.1157, 0.0922)
    a = (0.0, -0.612, -0.5723, 0.0, 0.0, 0.0)
    alpha = (np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0)
    rows = tuple(DHRow("revolute", al, ai, di, 0.0, f"q{i + 1}", Limits(-np.pi, np.pi))
                 for i, (al, ai, di) in enumerate(zip(alpha, a, d)))
    table = DHTable(rows)
    return Robot("ur10_like", chain_from_dh(table), table=table)


SIGMA = 0.05e-3                 # m, measurement noise per axis


def true_arm(robot, rng, every=True):
    """The nominal arm with every parameter moved by realistic amounts: the table's lengths by
    N(0, 0.5 mm), its angles (twists and joint offsets) by N(0, 0.2 deg), the base's and the
    tool's translations by N(0, 1 mm) and rotations by N(0, 0.5 deg). With every=False only
    the parameters identifiable at nominal (from 200 random configurations) are moved."""
    model = parametric_model(robot)
    moved = np.ones(len(model.names), dtype=bool)
    if not every:
        q = rng.uniform(robot.lower, robot.upper, (200, robot.n))
        _, J = evaluate(model, model.nominal, q)
        found = identifiability(J[:, :3].reshape(-1, len(model.names)), model.names)
        moved[:] = False
        moved[found.identifiable] = True
    frame = np.array([n.startswith(("T_base.", "T_tool.")) for n in model.names])
    size = np.where(model.angular, np.deg2rad(np.where(frame, 0.5, 0.2)),
                    np.where(frame, 1e-3, 0.5e-3))
    delta = rng.normal(size=len(moved)) * size
    return identified_robot(model, model.nominal + np.where(moved, delta, 0.0))


def scipy_reference(robot, q, measured, free):
    """The same parameters `free` fitted by least_squares with finite differences."""
    model = parametric_model(robot)

    def residual(x):
        params = model.nominal.copy()
        params[free] = x
        return (evaluate(model, params, q, False)[0][:, :3, 3] - measured).ravel()

    fit = least_squares(residual, model.nominal[free], jac="2-point", method="trf",
                        x_scale="jac")
    params = model.nominal.copy()
    params[free] = fit.x
    return model, params


def solve_times(f, rounds):
    """Wall time (min, median, max) and the median CPU time of the process (s) over rounds."""
    wall, cpu = [], []
    for _ in range(rounds):
        w, c = time.perf_counter(), time.process_time()
        f()
        cpu.append(time.process_time() - c)
        wall.append(time.perf_counter() - w)
    return (min(wall), float(np.median(wall)), max(wall)), float(np.median(cpu))


def kinematic(quick):
    print("\n## Kinematic calibration: hold-out mean position error (mm) before -> after; "
          "time per solve, wall min / median / max (CPU median)")
    print("| arm, measurements | armkit: hold-out mm | armkit: time | added at the fitted "
          "values | scipy least_squares (FD): hold-out mm | scipy: time | time ratio scipy / "
          "armkit | cond, O1 |")
    print("|---|---|---|---|---|---|---|---|")
    water, ur10 = armkit.robot("water_supply"), ur10_like()
    cases = [("water_supply", water, 10, False, True), ("water_supply", water, 30, False, True),
             ("water_supply", water, 10, True, True), ("UR10-like 6R", ur10, 700, False, True),
             ("UR10-like 6R", ur10, 700, False, False)]
    spread, ur10_data = {}, None
    for label, robot, n, chosen, every in cases:
        rng = np.random.default_rng(n)
        q, measured, hold, hold_p, result = _trial(robot, n, chosen, every, rng)
        t, cpu = solve_times(lambda r=robot, q=q, m=measured: calibrate(r, q, m),
                             rounds=10 if n > 100 else 5)
        free = np.flatnonzero(result.identifiable)
        model, params = scipy_reference(robot, q, measured, free)
        ref_hold = np.linalg.norm(evaluate(model, params, hold, False)[0][:, :3, 3] - hold_p,
                                  axis=-1)
        tr, _ = solve_times(lambda r=robot, q=q, m=measured: scipy_reference(r, q, m, free),
                            rounds=3 if quick else 5)
        name = (f"{label}, {n}" + (" chosen (D-optimal from 500)" if chosen else " random")
                + ("" if every else ", only parameters identifiable at nominal moved"))
        print(f"| {name} | {result.holdout_before.mean() * 1e3:.3f} -> "
              f"{result.holdout_after.mean() * 1e3:.4f} | {fmt_t(t)} ({cpu * 1e3:.1f} ms) | "
              f"{', '.join(result.added) or 'none'} | {ref_hold.mean() * 1e3:.4f} | "
              f"{fmt_t(tr)} | {tr[1] / t[1]:.1f} | "
              f"{result.condition_number:.3g}, {result.o1:.3g} |")
        if robot is water and n == 10:
            seeds = 10 if quick else 40
            spread[chosen] = [_trial(robot, n, chosen, every, np.random.default_rng([n, s]))[4]
                              .holdout_after.mean() * 1e3 for s in range(seeds)]
        if robot is ur10 and every:
            ur10_data = (q, measured, hold, hold_p, result)
    print(f"\nwater_supply, 10 measurements, {len(spread[True])} true arms and noise draws: "
          f"hold-out mean error after calibration, median (p90): random "
          f"{np.median(spread[False]):.4f} ({np.percentile(spread[False], 90):.4f}) mm, "
          f"D-optimal from a pool of 500 {np.median(spread[True]):.4f} "
          f"({np.percentile(spread[True], 90):.4f}) mm "
          f"({1 - np.median(spread[True]) / np.median(spread[False]):.0%} lower)")
    ur10_spread(ur10, 5 if quick else 20)
    pybotics(ur10, *ur10_data)


def ur10_spread(robot, arms):
    """Hold-out error over many true arms against what the noise alone allows."""
    model = parametric_model(robot)
    ours, nominal_only, floor, formula, added = [], [], [], [], 0
    for seed in range(arms):
        rng = np.random.default_rng([700, seed])
        actual = true_arm(robot, rng, True)
        hold = rng.uniform(robot.lower, robot.upper, (300, robot.n))
        hold_p = armkit.fk(actual, hold)[:, :3, 3]
        q = rng.uniform(robot.lower, robot.upper, (700, robot.n))
        exact = armkit.fk(actual, q)[:, :3, 3]
        noise = rng.normal(0, SIGMA, exact.shape)
        result = calibrate(robot, q, exact + noise, holdout=(hold, hold_p))
        ours.append(result.holdout_after.mean())
        added += len(result.added)
        nominal_only.append(calibrate(robot, q, exact + noise, holdout=(hold, hold_p),
                                      significance=np.inf).holdout_after.mean())
        # What the noise alone allows: the hold-out error of a correctly specified linear
        # least-squares fit (the parameters identifiable at the true arm, from noise-free
        # data) of this very noise draw.
        truth = calibrate(robot, q, exact)
        free = truth.identifiable
        _, J = evaluate(model, truth.identified, q)
        _, Jh = evaluate(model, truth.identified, hold)
        step = np.linalg.lstsq(J[:, :3, free].reshape(-1, free.sum()), noise.ravel(),
                               rcond=None)[0]
        floor.append(np.linalg.norm(Jh[:, :3, free] @ step, axis=-1).mean())
        # mean of a 3-D error of per-axis sigma sqrt(p / 3m): 2 sqrt(2 / pi) of that
        formula.append(2 * np.sqrt(2 / np.pi) * SIGMA * np.sqrt(free.sum() / (3 * len(q))))
    ours, nominal_only, floor = (np.array(v) * 1e3 for v in (ours, nominal_only, floor))
    print(f"\nUR10-like 6R, 700 measurements, {arms} true arms (every parameter moved) and "
          f"noise draws: hold-out mean error (mm), median / p90 / max; arms <= 0.01 mm")
    print("| fit | median | p90 | max | <= 0.01 mm |")
    print("|---|---|---|---|---|")
    for label, v in (("armkit (second pass at the fitted values)", ours),
                     ("armkit, nominal identifiability only (significance=inf)", nominal_only),
                     ("noise alone: correctly specified linear fit of the same noise", floor)):
        print(f"| {label} | {np.median(v):.4f} | {np.percentile(v, 90):.4f} | {v.max():.4f} | "
              f"{(v <= 0.01).sum()}/{arms} |")
    print(f"\nsigma * 2 sqrt(2/pi) * sqrt(p / 3m) with p identifiable at the true arm: "
          f"{np.median(formula) * 1e3:.4f} mm; parameters added per arm: {added / arms:.1f}; "
          f"armkit / noise alone, median of the ratios: {np.median(ours / floor):.3f}")


def pybotics(robot, q, measured, hold, hold_p, result):
    """pybotics' fit of the same data in its own interpreter, if ARMKIT_PYBOTICS_PYTHON names
    one (pybotics pins numpy < 2)."""
    python = os.environ.get("ARMKIT_PYBOTICS_PYTHON")
    if not python:
        print("\npybotics: not run (set ARMKIT_PYBOTICS_PYTHON to the python of an "
              "environment with pybotics installed; it pins numpy < 2).")
        return
    # The standard DH table as pybotics' modified DH: row k takes alpha and a of row k - 1,
    # the last row's a and alpha go to the tool (Tx(a) Rx(alpha) commute).
    rows = robot.table.rows
    mdh = np.array([[rows[k - 1].alpha if k else 0.0, rows[k - 1].a if k else 0.0,
                     rows[k].theta, rows[k].d] for k in range(len(rows))])
    tool = np.eye(4)
    c, s = np.cos(rows[-1].alpha), np.sin(rows[-1].alpha)
    tool[:3, :3] = [[1, 0, 0], [0, c, -s], [0, s, c]]
    tool[0, 3] = rows[-1].a
    tool = tool @ np.asarray(robot.table.T_tool)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "data.npz"
        np.savez(path, mdh=mdh, tool=tool, world=np.asarray(robot.table.T_base), q=q,
                 measured=measured, hold_q=hold)
        run = subprocess.run([python, str(Path(__file__).with_name("pybotics_fit.py")),
                              str(path)], capture_output=True, text=True)
    if run.returncode:
        print(f"\npybotics: failed ({(run.stderr.strip().splitlines() or ['no message'])[-1]})")
        return
    doc = json.loads(run.stdout)
    error = np.linalg.norm(np.array(doc["holdout_positions"]) - hold_p, axis=-1).mean()
    nominal = np.linalg.norm(np.array(doc["nominal_holdout_positions"]) - hold_p, axis=-1).mean()
    print(f"\npybotics (same data, UR10-like, 700 measurements, every parameter moved; its "
          f"OptimizationHandler with the whole chain, the tool position and the world frame "
          f"free, scipy least_squares on its residuals, at most 30 evaluations): hold-out mean "
          f"{nominal * 1e3:.3f} -> {error * 1e3:.4f} mm (armkit "
          f"{result.holdout_before.mean() * 1e3:.3f} -> {result.holdout_after.mean() * 1e3:.4f}), "
          f"one solve {doc['seconds']:.2f} s "
          f"({doc['evaluations']} evaluations, status {doc['status']}); largest parameter "
          f"change {doc['largest_length_change_m'] * 1e3:.1f} mm, "
          f"{np.rad2deg(doc['largest_angle_change_rad']):.2f} deg")


def _trial(robot, n, chosen, every, rng):
    """One true arm, n noisy measurements (random or D-optimal), a 300-point hold-out set."""
    actual = true_arm(robot, rng, every)
    hold = rng.uniform(robot.lower, robot.upper, (300, robot.n))
    hold_p = armkit.fk(actual, hold)[:, :3, 3]
    if chosen:
        pool = rng.uniform(robot.lower, robot.upper, (500, robot.n))
        q = pool[select_poses(robot, pool, n)]
    else:
        q = rng.uniform(robot.lower, robot.upper, (n, robot.n))
    measured = armkit.fk(actual, q)[:, :3, 3] + rng.normal(0, SIGMA, (n, 3))
    return q, measured, hold, hold_p, calibrate(robot, q, measured, holdout=(hold, hold_p))


def main():
    set_mode("compiled")        # compiled speed from the first call (armkit.jit)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="20 hand-eye trials per cell")
    args = parser.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.2f} (machine shared)")
    handeye_accuracy(20 if args.quick else 100)
    degenerate()
    kinematic(args.quick)
    print(f"\nload average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
