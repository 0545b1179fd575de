"""The readers under fuzz, a valid seed file for each, and what a loaded file comes to.

Each reader has a name (the fuzz table's row), a seed file written here from armkit's own
examples or built by hand as its users write them, the call that reads it, and `digest`: the
loaded object as nested tuples of rounded numbers and strings, so that a mutation that must not
change the result (a comment, keys reordered, another layout of the same cloud) can be held to
the same digest.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import struct
from pathlib import Path

import numpy as np
import yaml

from tests.io.test_scene import MOVEIT_OLD as MOVEIT

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"

PLAN = """units: {length: mm, angle: deg}
robot: inspection_6dof
radius: 40
obstacles:
  - {type: box, min: [650, -500, 200], max: [1100, 500, 240], name: lower plate}
  - {type: sphere, center: [400, 600, 500], radius: 100}
  - {type: cylinder, radius: 50, length: 400, xyz: [0, 600, 200], rpy: [0, 0, 30]}
  - {type: capsule, a: [0, -600, 0], b: [0, -600, 300], radius: 40}
start: [31.9, -91, 77.6, -135.9, 127.1, -141.1]
goal: [-50.2, -23.3, -77.5, 96.9, -53.4, 131.7]
planner: {name: rrtconnect, seed: 3, resolution: 5, waypoints: 10, time_limit: 2}
"""

SCENE = """units: {length: m, angle: rad}
obstacles:
  - {type: box, size: [0.1, 0.2, 0.3], xyz: [0.5, 0, 0.2], rpy: [0, 0, 0.5], name: crate}
  - {type: sphere, center: [0.4, 0.3, 0.2], radius: 0.08}
scene: cell.scene
"""

HANDEYE_RESULT = """units: {length: mm, angle: deg}
handeye:
  mode: eye_to_hand
  method: joint
  X: {xyz: [1200, 0, 800], rpy: [180, 0, 90]}
  target: {xyz: [0, 0, 100], rpy: [0, 0, 0]}
  std: {rotation: [0.01, 0.01, 0.02], translation: [0.1, 0.1, 0.2]}
  residuals_rms: {rotation: 0.02, translation: 0.3}
"""

CASE = """robot: inspection_6dof
start: [0, 0, 0, 0, 0, 0]
goal: [30, -45, 60, 0, 90, 0]
profiles: [quintic, jerk-limited]
duration: 10
velocity: 90
jerk: 600
sync: time
"""

RNG = np.random.default_rng(2026)
# A wall 1.5 m ahead with some spread: a plausible cloud, in mm.
CLOUD = np.column_stack([RNG.uniform(1400, 1600, 300), RNG.uniform(-400, 400, 300),
                         RNG.uniform(-300, 300, 300)]).astype("<f4")


def _pcd(data: str) -> bytes:
    header = ("# .PCD v0.7 - Point Cloud Data file format\n# units: mm\nVERSION 0.7\n"
              "FIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
              f"WIDTH {len(CLOUD)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {len(CLOUD)}\n"
              f"DATA {data}\n").encode()
    intensity = np.arange(len(CLOUD), dtype="<f4")
    if data == "ascii":
        rows = "\n".join(f"{x:.9g} {y:.9g} {z:.9g} {i:g}" for (x, y, z), i in
                         zip(CLOUD.tolist(), intensity.tolist()))
        return header + rows.encode() + b"\n"
    if data == "binary":
        table = np.column_stack([CLOUD, intensity]).astype("<f4")
        return header + table.tobytes()
    from armkit.io.clouds import lzf_compress
    raw = CLOUD[:, 0].tobytes() + CLOUD[:, 1].tobytes() + CLOUD[:, 2].tobytes() + \
        intensity.tobytes()
    packed = lzf_compress(raw)
    return header + struct.pack("<II", len(packed), len(raw)) + packed


def _ply(fmt: str) -> bytes:
    header = (f"ply\nformat {fmt} 1.0\ncomment units mm\nelement vertex {len(CLOUD)}\n"
              "property float x\nproperty float y\nproperty float z\nproperty uchar red\n"
              "element face 2\nproperty list uchar int vertex_indices\nend_header\n").encode()
    red = (np.arange(len(CLOUD)) % 256).astype("u1")
    if fmt == "ascii":
        rows = "\n".join(f"{x:.9g} {y:.9g} {z:.9g} {r}" for (x, y, z), r in
                         zip(CLOUD.tolist(), red.tolist()))
        return header + rows.encode() + b"\n3 0 1 2\n3 2 3 4\n"
    vertices = np.empty(len(CLOUD), [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("r", "u1")])
    vertices["x"], vertices["y"], vertices["z"], vertices["r"] = CLOUD.T[0], CLOUD.T[1], \
        CLOUD.T[2], red
    faces = np.array([(3, 0, 1, 2), (3, 2, 3, 4)], [("n", "u1"), ("a", "<i4"), ("b", "<i4"),
                                                     ("c", "<i4")])
    return header + vertices.tobytes() + faces.tobytes()


def _csv() -> bytes:
    rows = "\n".join(f"{x:.9g},{y:.9g},{z:.9g}" for x, y, z in CLOUD.tolist())
    return ("# units: mm\nx,y,z\n" + rows + "\n").encode()


def _waypoints_csv() -> bytes:
    return b"t,q1,q2,q3,q4,q5,q6\n0,0,0,0,0,0,0\n1,10,20,30,40,50,60\n2,20,30,40,50,60,70\n"


def _waypoints_json() -> bytes:
    return json.dumps({"q": [[0, 0, 0, 0, 0, 0], [10, 20, 30, 40, 50, 60]],
                       "t": [0, 1]}).encode()


# name -> (file name, seed bytes, text format family)
READERS = {
    "task": ("task.yaml", lambda: (EXAMPLES / "tasks" / "water_supply.task.yaml").read_bytes(),
             "yaml"),
    "plan": ("plan.yaml", lambda: PLAN.encode(), "yaml"),
    "scene": ("scene.yaml", lambda: SCENE.encode(), "yaml"),
    "moveit": ("cell.scene", lambda: MOVEIT.encode(), "lines"),
    "pcd_ascii": ("cloud.pcd", lambda: _pcd("ascii"), "pcd"),
    "pcd_binary": ("cloud.pcd", lambda: _pcd("binary"), "pcd"),
    "pcd_compressed": ("cloud.pcd", lambda: _pcd("binary_compressed"), "pcd"),
    "ply_ascii": ("cloud.ply", lambda: _ply("ascii"), "ply"),
    "ply_binary": ("cloud.ply", lambda: _ply("binary_little_endian"), "ply"),
    "cloud_csv": ("cloud.csv", _csv, "csv"),
    "handeye": ("poses.yaml",
                lambda: (EXAMPLES / "calibration" / "handeye_poses.yaml").read_bytes(), "yaml"),
    "camera": ("mount.yaml", lambda: HANDEYE_RESULT.encode(), "yaml"),
    "measurements": ("meas.csv", lambda: (EXAMPLES / "calibration" /
                                          "water_supply_measurements.csv").read_bytes(), "csv"),
    "accuracy": ("acc.csv", lambda: (EXAMPLES / "calibration" /
                                     "inspection_6dof_accuracy.csv").read_bytes(), "csv"),
    "register_map": ("drive.map.yaml", lambda: (EXAMPLES / "drives" /
                                                "inspection_6dof.map.yaml").read_bytes(), "yaml"),
    "waypoints_csv": ("wp.csv", _waypoints_csv, "csv"),
    "waypoints_json": ("wp.json", _waypoints_json, "json"),
    "trajectory_case": ("case.yaml", lambda: CASE.encode(), "yaml"),
}


def write_seed(name: str, folder: Path) -> Path:
    """Write reader `name`'s seed file (and the files it names) into `folder`."""
    file, make, _ = READERS[name]
    folder.mkdir(parents=True, exist_ok=True)
    if name == "scene":
        (folder / "cell.scene").write_text(MOVEIT)
    path = folder / file
    path.write_bytes(make())
    return path


@functools.lru_cache(maxsize=None)
def _robot(name: str):
    import armkit
    return armkit.robot(name)


def load(name: str, path: str):
    """Read `path` with reader `name`, as a user's call would."""
    from armkit.io import camera, clouds, handeye, measurements, register_maps, scene, tasks
    from armkit.io import trajectory_cases, waypoints

    if name == "task":
        return tasks.load_task(path)
    if name == "plan":
        return scene.read_planning_problem(path)
    if name in ("scene", "moveit"):
        return scene.read_scene(path)
    if name.startswith(("pcd", "ply", "cloud")):
        return clouds.read_cloud(path)
    if name == "handeye":
        return handeye.read_handeye_poses(path)
    if name == "camera":
        return camera.read_camera_mount(path)
    if name == "measurements":
        return measurements.read_measurements(path, _robot("water_supply"))
    if name == "accuracy":
        return measurements.read_accuracy(path)
    if name == "register_map":
        return register_maps.load_register_map(path)
    if name.startswith("waypoints"):
        return waypoints.read_waypoints(Path(path), _robot("inspection_6dof"))
    if name == "trajectory_case":
        return trajectory_cases.read_case(path)
    raise KeyError(name)


# Not content: where the file was, and the line numbers of its rows (a comment shifts them).
NOT_CONTENT = ("path", "source", "lines")


def digest(value, digits: int = 12, depth: int = 0):
    """A loaded object as nested tuples of numbers (`digits` significant) and strings."""
    if depth > 6:
        return "..."
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "fiu":
            return ("array", value.shape, tuple(float(f"{x:.{digits}g}") for x in
                                                value.astype(float).ravel()[:5000]))
        return ("array", value.shape, str(value.dtype))
    if isinstance(value, (bool, int, str)) or value is None:
        return value
    if isinstance(value, float):
        return float(f"{value:.{digits}g}")
    if isinstance(value, dict) or hasattr(value, "keys") and hasattr(value, "items"):
        return tuple(sorted((str(k), digest(v, digits, depth + 1)) for k, v in value.items()))
    if isinstance(value, (list, tuple)):
        return tuple(digest(v, digits, depth + 1) for v in value[:2000])
    if dataclasses.is_dataclass(value):
        return (type(value).__name__,) + tuple(
            (f.name, digest(getattr(value, f.name), digits, depth + 1))
            for f in dataclasses.fields(value) if f.name not in NOT_CONTENT)
    if type(value).__name__ == "Robot":
        return ("Robot", value.name, value.n)
    if hasattr(value, "__dict__"):
        return (type(value).__name__,) + tuple(
            (k, digest(v, digits, depth + 1)) for k, v in sorted(vars(value).items())
            if not k.startswith("_") and not callable(v) and k not in NOT_CONTENT)
    return repr(value)[:200]


def yaml_text(document) -> str:
    return yaml.safe_dump(document, sort_keys=False, default_flow_style=None, width=1000)


def close(a, b, rtol: float) -> bool:
    """Whether two digests are equal, their numbers within `rtol` (relative) of each other."""
    if isinstance(a, float) and isinstance(b, float):
        return abs(a - b) <= rtol * max(abs(a), abs(b), 1e-300) or a == b
    if isinstance(a, tuple) and isinstance(b, tuple):
        return len(a) == len(b) and all(close(x, y, rtol) for x, y in zip(a, b))
    return a == b
