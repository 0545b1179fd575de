"""Every subcommand against a table of bad or extreme input: exit 2, exactly one stderr line
naming the argument, no traceback, nothing on stdout, and no hang.

The table runs in one separate Python process (``python -m tests.cli.test_bad_input_table
FOLDER``) that imports the app once and feeds it each row through typer's CliRunner, under a
time-out, so a hang fails the test instead of stopping the suite; a few rows also run as the
real command in their own processes.
"""

from __future__ import annotations

import json
import subprocess
import sys
import traceback
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = str(ROOT / "examples" / "tool_changer_table1.yaml")
MAP = str(ROOT / "examples" / "drives" / "inspection_6dof.map.yaml")
LONG = "x" * 300
P2P = ("--start=0,0,0,0,0,0", "--goal=30,0,0,0,0,0")
ROW_SECONDS = 60        # a hang bound per row (the table's process is waited on this long each)

# (arguments, words the one stderr line must hold). "{tmp}" is the folder of helper files
# (see `helper_files`), made by the process that runs the table.
ROWS: list[tuple[tuple[str, ...], str]] = [
    # the group itself
    (("nosuch",), "COMMAND: expected one of robots, show, fk, handeye, calibrate, accuracy"),
    (("fk0", "ur5"), "did you mean fk?"),
    (("--bogus",), "--bogus: expected an option of `armkit` (--help), found an unknown option"),
    # robots
    (("robots", "--bogus"), "--bogus: expected an option of `armkit robots`"),
    (("robots", "extra"), "armkit robots: expected no more arguments, found 'extra'"),
    (("robots", "--json", "x"), "armkit robots: expected no more arguments, found 'x'"),
    # show
    (("show",), "ROBOT: expected a value, found none"),
    (("show", "ur6"), "robot: expected a built-in name"),
    (("show", LONG), "robot: expected a built-in name or a robot file, found a name of 300 "
                     "characters (at most 255)"),
    (("show", LONG + ".yaml"), "robot: expected a built-in name or a robot file, found a name "
                               "of 305 characters"),
    (("show", "missing.yaml"), "expected a built-in name"),
    (("show", ""), "robot: expected a built-in name"),
    (("show", "ur5", "--bogus"), "--bogus: expected an option of `armkit show`"),
    (("show", "ur5", "extra"), "armkit show: expected no more arguments, found 'extra'"),
    (("show", "{tmp}/bad_arm.yaml"), "{tmp}/bad_arm.yaml: joints[0].a: expected a valid number"),
    (("show", "{tmp}/empty.yaml"), "{tmp}/empty.yaml"),
    (("show", "{tmp}/broken.yaml"), "{tmp}/broken.yaml: line "),
    # warm-up
    (("warm-up", "--only", "foo"), "--only: expected some of kinematics, ik, trajectory, "
                                   "planning, workspace (commas between), found 'foo'"),
    (("warm-up", "--only", ""), "--only: expected some of"),
    (("warm-up", "extra"), "armkit warm-up: expected no more arguments, found 'extra'"),
    # fk
    (("fk", "ur5", "a", "b", "c", "d", "e", "f"), "Q: expected a number from -1e+09 to 1e+09, "
                                                  "found 'a'"),
    (("fk", "ur5", "0", "0", "0", "0", "0", "x"), "Q: expected a number from -1e+09 to 1e+09, "
                                                  "found 'x'"),
    (("fk", "ur5", "1", "2"), "Q: expected 6 joint values for ur5, found 2"),
    (("fk", "ur5", "0", "0", "0", "0", "0", "0", "0"), "Q: expected 6 joint values for ur5, "
                                                       "found 7"),
    (("fk", "ur5"), "Q: expected a value, found none"),
    (("fk", "ur5", "nan", "0", "0", "0", "0", "0"), "Q: expected a finite number"),
    (("fk", "ur5", "inf", "0", "0", "0", "0", "0"), "Q: expected a finite number"),
    (("fk", "ur5", "1e308", "0", "0", "0", "0", "0"), "Q: expected a number from -1e+09 to "
                                                      "1e+09, found 1e+308"),
    (("fk", "ur5", "-1e155", "0", "0", "0", "0", "0"), "found -1e+155"),
    (("fk", "ur5", "0x10", "0", "0", "0", "0", "0"), "Q: expected a number"),
    (("fk", "ur5", "--bogus"), "--bogus: expected an option of `armkit fk` (--help, --json, "
                               "--si), found an unknown option"),
    (("fk", "ur5", "0", "0", "0", "0", "0", "0", "--jsn"), "did you mean --json?"),
    (("fk", LONG, "0"), "robot: expected a built-in name or a robot file, found a name of 300"),
    (("fk", "ur6", "0"), "robot: expected a built-in name"),
    # ik: argument validation and messages
    (("ik", "ur5"), "--pose: expected a value, found none"),
    (("ik", "ur5", "--pose", "1", "2"), "--pose: expected 3 values, found fewer"),
    (("ik", "ur5", "--pose", "0.4,0.1,0.3"), "--pose: expected 3 values, found fewer"),
    (("ik", "ur5", "--pose", "a", "0", "0"), "--pose: expected a number from -1e+09 to 1e+09, "
                                             "found 'a'"),
    (("ik", "ur5", "--pose", "1e155", "0", "0"), "--pose: expected a number from -1e+09 to "
                                                 "1e+09, found 1e+155"),
    (("ik", "ur5", "--pose", "-1e10", "0", "0"), "--pose: expected a number"),
    (("ik", "ur5", "--pose", "nan", "0", "0"), "--pose: expected a finite number"),
    (("ik", "ur5", "--pose", "0.4", "0.1", "0.3", "--rpy", "0", "0"),
     "--rpy: expected 3 values, found fewer"),
    (("ik", "ur5", "--pose", "0.4", "0.1", "0.3", "--rpy", "1e308", "0", "0"),
     "--rpy: expected a number from -4e+08 to 4e+08, found 1e+308"),
    (("ik", "ur5", "--pose", "0.4", "0.1", "0.3", "--yaw", "x"), "--yaw: expected a number"),
    (("ik", "ur5", "--pose", "0.4", "0.1", "0.3", "--yaw", "inf"), "--yaw: expected a finite"),
    (("ik", "ur5", "--pose", "0.4", "0.1", "0.3", "--pitch", "1e300"), "--pitch: expected a "
                                                                      "number"),
    (("ik", "ur5", "--pose", "0.4", "0.1", "0.3", "--q0", "1 2"),
     "--q0: expected 6 numbers separated by spaces or commas, found 2"),
    (("ik", "ur5", "--pose", "0.4", "0.1", "0.3", "--q0", "a b c d e f"),
     "--q0: expected a number from -1e+09 to 1e+09, found 'a'"),
    (("ik", "ur5", "--pose", "0.4", "0.1", "0.3", "--q0", "nan,0,0,0,0,0"),
     "--q0: expected a finite number"),
    (("ik", "ur5", "--pose", "0.4", "0.1", "0.3", "--rpy", "0", "0", "0", "--yaw", "1"),
     "--rpy, --yaw: expected one of them, found 2"),
    (("ik", "ur5", "--pose", "0.4", "0.1", "0.3", "--mask", "bogus"), "mask"),
    (("ik", "ur5", "--pose", "0.4", "0.1", "0.3", "--method", "bogus"), "method"),
    (("ik", "ur5", "--pose", "0.4", "0.1", "0.3", "--criterion", "bogus"), "criterion"),
    (("ik", LONG, "--pose", "0", "0", "0"), "robot: expected a built-in name or a robot file, "
                                            "found a name of 300"),
    (("ik", "ur5", "--pose", "0", "0", "0", "--bogus"), "--bogus: expected an option of "
                                                        "`armkit ik`"),
    # workspace
    (("workspace", "ur5", "-n", "0"), "-n: expected a whole number from 1 to 1e+10 samples in "
                                      "this process (--scheduler for more), found 0"),
    (("workspace", "ur5", "-n", "lots"), "-n: expected a whole number"),
    (("workspace", "ur5", "-n", "2.5"), "-n: expected a whole number"),
    (("workspace", "ur5", "-n", "1e20"), "-n: expected a whole number from 1 to 1e+10 samples "
                                         "in this process (--scheduler for more), found 1e+20"),
    (("workspace", "ur5", "-n", "1e20", "--scheduler", "tcp://127.0.0.1:8786"),
     "-n: expected a whole number from 1 to 1e+12 samples on Dask, found 1e+20"),
    (("workspace", "ur5", "-n", "nan"), "-n: expected a finite number"),
    (("workspace", "ur5", "-n", "-5"), "-n: expected a whole number"),
    (("workspace", "ur5", "--seed", "-1"), "--seed: expected a whole number from 0 to 1e+18"),
    (("workspace", "ur5", "--seed", "x"), "--seed: expected a whole number"),
    (("workspace", "ur5", "--seed", "1.5"), "--seed: expected a whole number"),
    (("workspace", "ur5", "--resolution", "-5"), "--resolution: expected a number above 0 and "
                                                 "at most 1e+09, found -5"),
    (("workspace", "ur5", "--resolution", "0"), "--resolution: expected a number above 0"),
    (("workspace", "ur5", "--resolution", "1e308"), "--resolution: expected a number above 0 "
                                                    "and at most 1e+09, found 1e+308"),
    (("workspace", "ur5", "--resolution", "nan"), "--resolution: expected a finite number"),
    (("workspace", "ur5", "--resolution", "1e-300"), "resolution: expected at least"),
    (("workspace", "ur5", "--height", "1e308"), "--height: expected a number from -1e+09 to "
                                                "1e+09, found 1e+308"),
    (("workspace", "ur5", "--height", "x"), "--height: expected a number"),
    (("workspace", "ur5", "--azimuth", "inf"), "--azimuth: expected a finite number"),
    (("workspace", "ur5", "--azimuth", "1e300"), "--azimuth: expected a number from -1e+06"),
    (("workspace", "ur5", "--scheduler", "nowhere"), "scheduler: expected an address such as "
                                                     "tcp://127.0.0.1:8786, found 'nowhere'"),
    (("workspace", "ur5", "--scheduler", ""), "scheduler: expected an address such as "
                                              "tcp://127.0.0.1:8786, found ''"),
    (("workspace", "ur5", "--scheduler", "tcp://127.0.0.1:99999"), "(a host and a port "
                                                                   "1..65535)"),
    (("workspace", "ur5", "--scheduler", "bogus://127.0.0.1:1"), "(schemes: inproc"),
    (("workspace", LONG), "robot: expected a built-in name or a robot file, found a name of"),
    (("workspace", "ur5", "--bogus"), "--bogus: expected an option of `armkit workspace`"),
    (("workspace", "ur5", "--out", "/dev/null/sub"), "--out: expected a folder armkit can "
                                                     "write, found '/dev/null/sub'"),
    # traj
    (("traj", "ur5", "--start=0,0,0,0,0,0"), "expected start and goal"),
    (("traj", "ur5", "--start=0,0,0", "--goal=1,1,1"), "start: expected 6 joint values"),
    (("traj", "ur5", "--start=0,0,0,0,0,0", "--goal=1,1,1,1,1,1", "--profile", "jerk-limited"),
     "jerk: expected a jerk limit"),
    (("traj", "ur5", "--start=0,0,0,0,0,0", "--goal=1,1,1,1,1,1", "--profile", "spline"),
     "profiles[0]"),
    (("traj", EXAMPLE, "--pattern", "3-3"), "degrees: expected 3 segment degrees"),
    (("traj", EXAMPLE, "--joints", "2,3,wrist"), "joints: expected joint numbers 1..6"),
    (("traj", "ur5", "--times", "0,1", "--point=1,2,3,4,5,6", "--point=1,x"),
     "--point: expected a number from -1e+09 to 1e+09, found 'x'"),
    (("traj", "ur5", "--start=0,0,0,0,0,0", "--goal=0,0,0,0,0,0"),
     "goal: expected a configuration other than the start"),
    (("traj", "inspection_6dof", "--start=0,0,0,0,0,0", "--goal=300,0,0,0,0,0"),
     "goal: expected joint 1 (q1) within its limits -180 .. 180 deg, found 300"),
    (("traj", "inspection_6dof", *P2P, "--duration", "1e308"),
     "--duration: expected a number from 1e-06 to 1e+06 s, found 1e+308"),
    (("traj", "inspection_6dof", *P2P, "--duration", "0"), "--duration: expected a number "
                                                           "from 1e-06 to 1e+06 s, found 0"),
    (("traj", "inspection_6dof", *P2P, "--duration", "x"), "--duration: expected a number"),
    (("traj", "inspection_6dof", *P2P, "--profile", "jerk-limited", "--jerk", "1e-300"),
     "--jerk: expected a number from 1e-06 to 1e+09, found 1e-300"),
    (("traj", "inspection_6dof", *P2P, "--velocity", "-5"), "--velocity: expected a number "
                                                            "from 1e-06 to 1e+09, found -5"),
    (("traj", "inspection_6dof", *P2P, "--velocity", "nan"), "--velocity: expected a finite"),
    (("traj", "inspection_6dof", *P2P, "--acceleration", "1e308"), "--acceleration: expected "
                                                                   "a number"),
    (("traj", "inspection_6dof", *P2P, "--velocity", "1,2"), "velocity: expected one value or "
                                                             "6 (one per joint), found 2"),
    (("traj", "ur5", "--times", "0,x", "--point=0,0,0,0,0,0"), "--times: expected a number"),
    (("traj", "ur5", "--times", "0,1e308", "--point=0,0,0,0,0,0"),
     "--times: expected a number from -1e+06 to 1e+06, found 1e+308"),
    (("traj", "ur5", "--start=nan,0,0,0,0,0", "--goal=1,0,0,0,0,0"),
     "--start: expected a finite number"),
    (("traj", "modular_4dof", "--times", "0,1,2", "--joints", "2", "--point=0", "--point=500",
      "--point=0"), "points[1]: expected joint 2 (shoulder) within its limits -105 .. 105 deg, "
                    "found 500"),
    (("traj", EXAMPLE, "--hold=0,0,0,900,0,0"), "hold: expected joint 4 (telescope) within its "
                                                "limits 0 .. 800 mm, found 900"),
    (("traj", "nope.yaml"), "case: expected a case file or a robot, found no file nope.yaml"),
    (("traj", LONG), "case: expected a built-in name or a robot file, found a name of 300"),
    (("traj", LONG + ".yaml"), "case: expected a built-in name or a robot file, found a name "
                               "of 305"),
    (("traj", "{tmp}/long_duration.yaml"), "{tmp}/long_duration.yaml: duration: expected a "
                                           "number above 0 and at most 1e+06, found 1e+308"),
    (("traj", "{tmp}/typo_case.yaml"), "{tmp}/typo_case.yaml: top level: expected one of"),
    (("traj", "{tmp}/broken.yaml"), "{tmp}/broken.yaml: line "),
    (("traj", "{tmp}/long_robot_case.yaml"), "robot: expected a built-in name or a robot file"),
    (("traj", "ur5", "--bogus"), "--bogus: expected an option of `armkit traj`"),
    (("traj", "ur5", *P2P[:1], "--goal=1,0,0,0,0,0", "--sync", "diagonal"), "sync"),
    (("traj", "ur5", *P2P[:1], "--goal=1,0,0,0,0,0", "--out", "/dev/null/x"),
     "--out: expected a folder armkit can write"),
    # run, demo, view (the end-to-end job)
    (("run",), "TASK: expected a value, found none"),
    (("run", "{tmp}/missing.yaml"), "{tmp}/missing.yaml: expected a readable file"),
    (("run", "{tmp}/broken.yaml"), "{tmp}/broken.yaml: line "),
    (("run", "{tmp}/empty.yaml"), "{tmp}/empty.yaml: top level: expected a mapping of task"),
    (("run", "x.yaml", "--bogus"), "--bogus: expected an option of `armkit run`"),
    (("demo", "extra"), "armkit demo: expected no more arguments, found 'extra'"),
    (("demo", "--bogus"), "--bogus: expected an option of `armkit demo`"),
    (("demo", "--out", "/dev/null/x"), "--out: expected a folder armkit can write"),
    (("view", "ur5", "0", "0"), "Q: expected 6 joint values for ur5, found 2"),
    (("view", "ur5", "nan", "0", "0", "0", "0", "0"), "Q: expected a finite number"),
    (("view", "ur5", "1e308", "0", "0", "0", "0", "0"), "Q: expected a number from -1e+09"),
    (("view", LONG), "robot: expected a built-in name or a robot file, found a name of 300"),
    (("view", "ur5", "--out", "view.png"), "--out: expected a file ending in .html, .htm, found "
                                           "'view.png'"),
    (("view", "ur5", "--out", "/dev/null/v.html"), "--out: expected a file in an existing "
                                                   "folder"),
    # plan, calibration, detect (their own tests hold their full tables)
    (("plan", "{tmp}/missing.yaml"), "{tmp}/missing.yaml: expected a readable file"),
    (("plan", "x.yaml", "--bogus"), "--bogus: expected an option of `armkit plan`"),
    (("handeye", "{tmp}/missing.yaml"), "{tmp}/missing.yaml: expected a readable file"),
    (("handeye", "x.yaml", "--bogus"), "--bogus: expected an option of `armkit handeye`"),
    (("calibrate", "ur5", "{tmp}/missing.csv"), "{tmp}/missing.csv: expected a readable file"),
    (("calibrate", LONG, "x.csv"), "robot: expected a built-in name or a robot file, found "
                                   "'xxxx"),
    (("accuracy", "{tmp}/missing.csv"), "{tmp}/missing.csv: expected a readable file"),
    (("accuracy", "x.csv", "--bogus"), "--bogus: expected an option of `armkit accuracy`"),
    (("detect", "{tmp}/missing.pcd"), "{tmp}/missing.pcd: expected a readable file"),
    (("detect", "{tmp}/wp.csv", "--bogus"), "--bogus: expected an option of `armkit detect`"),
    # send
    (("send", "{tmp}/wp.csv"), "--map: expected a value, found none"),
    (("send", "{tmp}/missing.csv", "--map", MAP), "{tmp}/missing.csv: expected a readable file"),
    (("send", "{tmp}/wp.csv", "--map", "missing.map.yaml"), "missing.map.yaml: expected a "
                                                            "readable file"),
    (("send", "{tmp}/wp.csv", "--map", MAP, "--timeout", "0"),
     "--timeout: expected a number from 0.001 to 3600 s, found 0"),
    (("send", "{tmp}/wp.csv", "--map", MAP, "--timeout", "1e308"),
     "--timeout: expected a number from 0.001 to 3600 s, found 1e+308"),
    (("send", "{tmp}/wp.csv", "--map", MAP, "--timeout", "x"), "--timeout: expected a number"),
    (("send", "{tmp}/wp.csv", "--map", MAP, "--port", "70000"),
     "--port: expected a whole number from 1 to 65535, found 70000"),
    (("send", "{tmp}/wp.csv", "--map", MAP, "--port", "x"), "--port: expected a whole number"),
    (("send", "{tmp}/wp.csv", "--map", MAP, "--port", "0"), "--port: expected a whole number "
                                                            "from 1 to 65535, found 0"),
    (("send", "{tmp}/wp.csv", "--map", MAP, "--retries", "-1"), "--retries: expected a whole "
                                                                "number from 0 to 100"),
    (("send", "{tmp}/wp.csv", "--map", MAP, "--retries", "1e9"), "--retries: expected a whole "
                                                                 "number from 0 to 100"),
    (("send", "{tmp}/nan.csv", "--map", MAP), "{tmp}/nan.csv: line 3, column 2: expected a "
                                              "valid number"),
    (("send", "{tmp}/inf.csv", "--map", MAP), "{tmp}/inf.csv: line 1, column 2: expected a "
                                              "valid number"),
    (("send", "{tmp}/short.csv", "--map", MAP), "{tmp}/short.csv: line 1: expected 6 numbers"),
    (("send", "{tmp}/empty.csv", "--map", MAP), "{tmp}/empty.csv: expected waypoints"),
    (("send", "{tmp}/nan.json", "--map", MAP), "{tmp}/nan.json: q[1][2]: expected a finite "
                                               "number"),
    (("send", "{tmp}/broken.json", "--map", MAP), "{tmp}/broken.json: line 1: expected valid "
                                                  "JSON"),
    (("send", "{tmp}/wp.csv", "--map", MAP, "--robot", LONG), "--robot: expected a built-in "
                                                              "name or a robot file"),
    (("send", "{tmp}/wp.csv", "--map", MAP, "--bogus"), "--bogus: expected an option of "
                                                        "`armkit send`"),
    (("send", "{tmp}/far.csv", "--map", MAP, "--dry-run"), "waypoint 1, joint q1: 190 deg "
                                                           "outside the limits"),
    # sim-drive: every row fails before it listens
    (("sim-drive", "--port", "70000"), "--port: expected a whole number from 0 to 65535, "
                                       "found 70000"),
    (("sim-drive", "--port", "x"), "--port: expected a whole number"),
    (("sim-drive", "--port", "-1"), "--port: expected a whole number from 0 to 65535"),
    (("sim-drive", "--map", "{tmp}/missing.map.yaml"), "{tmp}/missing.map.yaml: expected a "
                                                       "readable file"),
    (("sim-drive", "--robot", LONG), "--robot: expected a built-in name or a robot file"),
    (("sim-drive", "--bogus"), "--bogus: expected an option of `armkit sim-drive`"),
    (("sim-drive", "extra"), "armkit sim-drive: expected no more arguments, found 'extra'"),
    # dynamics
    (("dynamics", "ur5"), "--q: expected a value, found none"),
    (("dynamics", "ur5", "--q", "0 0 0"), "--q: expected 6 values (the joints of ur5), found 3"),
    (("dynamics", "ur5", "--q", "0 0 0 0 0 x"), "--q: expected a number from -1e+09 to 1e+09, "
                                                "found 'x'"),
    (("dynamics", "ur5", "--q", "0 0 0 0 0 nan"), "--q: expected a finite number"),
    (("dynamics", "ur5", "--q", "0 0 0 0 0 1e308"), "--q: expected a number from -1e+09 to "
                                                    "1e+09, found 1e+308"),
    (("dynamics", "ur5", "--q", "0,0,0,0,0,0", "--qd", "1 2"), "--qd: expected 6 values"),
    (("dynamics", "ur5", "--q", "0,0,0,0,0,0", "--qdd", "inf,0,0,0,0,0"),
     "--qdd: expected a finite number"),
    (("dynamics", "ur5", "--q", "0,0,0,0,0,0", "--payload", "-1"),
     "--payload: expected a number from 0 to 10000 kg, found -1"),
    (("dynamics", "ur5", "--q", "0,0,0,0,0,0", "--payload", "1 2"),
     "--payload: expected MASS or MASS X Y Z (kg, m), found 2 numbers"),
    (("dynamics", "ur5", "--q", "0,0,0,0,0,0", "--payload", ""),
     "--payload: expected numbers separated by spaces or commas, found none"),
    (("dynamics", "stanford", "--q", "0,0,0.5,0,0,0"), "robot stanford: expected inertial "
                                                       "parameters"),
    (("dynamics", "ur6", "--q", "0"), "robot: expected a built-in name"),
    (("dynamics", "ur5", "--q", "0,0,0,0,0,0", "--bogus"), "--bogus: expected an option of "
                                                           "`armkit dynamics`"),
    # demo
    (("demo", "--bogus"), "--bogus: expected an option of `armkit demo`"),
    (("demo", "extra"), "armkit demo: expected no more arguments, found 'extra'"),
    (("demo", "--out", "/dev/null/x"), "--out: expected a folder armkit can write"),
    # reach, place: every row fails before a map is solved
    (("reach",), "ROBOT: expected a value, found none"),
    (("reach", "ur5", "--resolution", "-5"), "--resolution: expected a number above 0"),
    (("reach", "ur5", "--resolution", "1e-6"), "resolution: expected at least"),
    (("reach", "ur5", "--orientations", "1.5"), "--orientations: expected a whole number"),
    (("reach", "ur5", "--method", "x"), "--method: expected one of auto, analytic, lm, newton"),
    (("reach", "ur5", "--scene", "{tmp}/broken.yaml"), "{tmp}/broken.yaml: line "),
    (("reach", "ur5", "--out", "/dev/null/x"), "--out: expected a folder armkit can write"),
    (("reach", "ur5", "--bogus"), "--bogus: expected an option of `armkit reach`"),
    (("place", "ur5"), "TASKS: expected a value, found none"),
    (("place", "ur5", "{tmp}/empty.yaml"), "{tmp}/empty.yaml: expected a mapping of fields"),
    (("place", "ur5", "{tmp}/broken.yaml"), "{tmp}/broken.yaml: line "),
    (("place", "ur5", "{tmp}/wp.csv", "--map", "{tmp}/wp.csv"), "{tmp}/wp.csv: expected"),
    (("place", "ur5", "{tmp}/empty.yaml", "--bogus"), "--bogus: expected an option of "
                                                      "`armkit place`"),
]


def helper_files(tmp: Path) -> None:
    """The files the rows name, each wrong in one way."""
    header = "q1,q2,q3,q4,q5,q6\n"
    files = {
        "bad_arm.yaml": "name: x\nunits: {length: mm, angle: deg}\nconvention: dh\njoints:\n"
                        "  - {type: revolute, alpha: 0, a: ten, d: 0, theta: 0}\n",
        "empty.yaml": "",
        "broken.yaml": "robot: [ur5\n",
        "long_duration.yaml": "robot: ur5\nstart: [0, 0, 0, 0, 0, 0]\ngoal: [1, 0, 0, 0, 0, 1]\n"
                              "duration: 1e308\n",
        "typo_case.yaml": "robot: ur5\ntimes: [0, 1]\npoints: [[0, 0, 0, 0, 0, 0], "
                          "[1, 1, 1, 1, 1, 1]]\npattrens: [3]\n",
        "long_robot_case.yaml": f"robot: {LONG}\nstart: [0]\ngoal: [1]\n",
        "wp.csv": header + "0,0,0,0,0,0\n10,20,30,40,50,60\n",
        "nan.csv": header + "0,0,0,0,0,0\n1,nan,0,0,0,0\n",
        "inf.csv": "0,inf,0,0,0,0\n",
        "short.csv": "1,2,3\n",
        "empty.csv": "\n",
        "far.csv": header + "0,0,0,0,0,0\n190,0,0,0,0,0\n",
        "nan.json": '{"q": [[0, 0, 0, 0, 0, 0], [1, 2, NaN, 4, 5, 6]]}',
        "broken.json": '{"q": [[0, 0',
    }
    for name, text in files.items():
        (tmp / name).write_text(text)


def _fill(args: tuple[str, ...], tmp: Path) -> list[str]:
    return [a.replace("{tmp}", str(tmp)) for a in args]


def run_table(tmp: Path) -> list[dict]:
    """Each row through CliRunner in this process: exit code, stdout, stderr, any exception
    that escaped."""
    from typer.testing import CliRunner

    from armkit.cli import app

    helper_files(tmp)
    runner = CliRunner()
    out = []
    for args, _ in ROWS:
        result = runner.invoke(app, _fill(args, tmp))
        escaped = result.exception if not isinstance(result.exception, SystemExit) else None
        out.append({"exit": result.exit_code, "stdout": result.stdout,
                    "stderr": result.stderr,
                    "exception": "".join(traceback.format_exception(escaped))
                    if escaped else ""})
    return out


@pytest.fixture(scope="module")
def table(tmp_path_factory) -> tuple[list[dict], Path]:
    tmp = tmp_path_factory.mktemp("bad")
    done = subprocess.run([sys.executable, "-m", "tests.cli.test_bad_input_table", str(tmp)],
                          cwd=ROOT, capture_output=True, text=True,
                          timeout=ROW_SECONDS * 10 + 5 * len(ROWS))
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.splitlines()[-1]), tmp


def test_the_table_is_large_and_covers_every_subcommand():
    from typer.main import get_command

    from armkit.cli import app

    assert len(ROWS) >= 100
    commands = set(get_command(app).commands)
    assert commands <= {args[0] for args, _ in ROWS}


@pytest.mark.parametrize("index", range(len(ROWS)),
                         ids=[" ".join(a)[:60] for a, _ in ROWS])
def test_bad_input_is_exit_2_and_one_line_naming_it(table, index):
    results, tmp = table
    (_, words), result = ROWS[index], results[index]
    words = words.replace("{tmp}", str(tmp))
    assert not result["exception"], result["exception"]
    assert result["exit"] == 2, (result["stdout"], result["stderr"])
    lines = result["stderr"].splitlines()
    assert len(lines) == 1 and lines[0].startswith("armkit: "), result["stderr"]
    assert words in lines[0]
    assert result["stdout"] == "" and "Traceback" not in result["stderr"]


# A few rows as the real command, each in its own process, all at once.
REAL = [("fk", "ur5", "a", "b", "c", "d", "e", "f"), ("ik", "ur5", "--pose", "1e155", "0", "0"),
        ("workspace", "ur5", "-n", "1e20"), ("show", LONG), ("fk", "ur5", "--bogus"),
        ("traj", "inspection_6dof", *P2P, "--profile", "jerk-limited", "--jerk", "1e-300"),
        ("send", "{tmp}/wp.csv", "--map", MAP, "--timeout", "1e308")]


def test_real_commands_give_one_line_and_no_traceback(tmp_path):
    helper_files(tmp_path)
    words = dict(ROWS)
    processes = [subprocess.Popen([sys.executable, "-m", "armkit", *_fill(args, tmp_path)],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                 for args in REAL]
    try:
        for args, process in zip(REAL, processes):
            stdout, stderr = process.communicate(timeout=300)
            assert process.returncode == 2, stderr
            assert stdout == "" and len(stderr.splitlines()) == 1, stderr
            assert words[args].replace("{tmp}", str(tmp_path)) in stderr
    finally:
        for process in processes:
            if process.poll() is None:
                process.kill()


if __name__ == "__main__":
    print(json.dumps(run_table(Path(sys.argv[1]))))
