"""MotionBenchMaker-style planning problems for the UR5 and the Panda of example-robot-data, and an
independent checker of planned paths.

Robots. Each arm's URDF and SRDF come from the installed example-robot-data; its collision
meshes are covered by spheres (`armkit.planning.spheres.spheres_from_mesh`, 2 cm tolerance) and
written as a spherized URDF (every <collision> a <sphere>, as VAMP's, cuRobo's and MoveIt users'
spherized URDFs are), which armkit then reads as any user's. The Panda's finger joints become
fixed (fingers closed), so that its hand and fingers are part of the arm, as in
MotionBenchMaker's Panda. The files are written once into a cache folder.

Problem families (after MotionBenchMaker's; obstacles placed in a frame in front of the arm,
that frame moved by a random offset and yaw for each problem): bookshelf_small (a shelf of
three compartments), bookshelf_tall (five), bookshelf_thin (thin plates, shallow
compartments), box (an open box on a table), table_pick (cans on a table), cage (posts, plates
and bars around a small room). Start and goal are valid configurations whose tool origin lies
in the family's start and goal regions (rejection sampling over random configurations, seeded),
and the straight joint-space edge between them is not free: the problem needs planning.

The independent checker places the spherized URDF's spheres with Pinocchio's forward kinematics
(not armkit's), tests them against the obstacles with NumPy point distances and against each
other for every pair of links the SRDF does not disable (links rigidly joined excepted), at
states no more than 0.005 rad apart on any joint along a path.

    python benchmarks/mbm.py            # builds the robots and prints a summary of the problems
"""

from __future__ import annotations

import importlib.metadata
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import armkit
from armkit.planning import Box, CollisionChecker, CollisionModel, Cylinder, Scene
from armkit.planning.spheres import spheres_from_mesh
from armkit.spatial import pose_from_xyz_rpy

CACHE = Path(os.environ.get("ARMKIT_BENCH_CACHE", Path(__file__).parent / ".cache"))
TOLERANCE = 0.02
FAMILIES = ("bookshelf_small", "bookshelf_tall", "bookshelf_thin", "box", "table_pick", "cage")
ARMS = {
    "ur5": ("ur_description/urdf/ur5_robot.urdf", "ur_description/srdf/ur5.srdf", "ee_link"),
    "panda": ("panda_description/urdf/panda.urdf", "panda_description/srdf/panda.srdf",
              "panda_hand"),
}


def data_file(suffix: str) -> Path:
    """The installed example-robot-data file whose path ends with `suffix`."""
    dist = importlib.metadata.distribution("example-robot-data")
    found = [f for f in dist.files or () if str(f).replace("\\", "/").endswith(suffix)]
    if len(found) != 1:
        raise FileNotFoundError(f"example-robot-data holds {len(found)} files ending {suffix}")
    return Path(dist.locate_file(found[0]))


def _xyz_rpy(element) -> np.ndarray:
    origin = element.find("origin")
    xyz = [0.0] * 3 if origin is None else [float(v) for v in origin.get("xyz", "0 0 0").split()]
    rpy = [0.0] * 3 if origin is None else [float(v) for v in origin.get("rpy", "0 0 0").split()]
    return pose_from_xyz_rpy(xyz, rpy)


def spherized_urdf(arm: str) -> tuple[Path, Path, str]:
    """(spherized URDF, SRDF, tip) of an arm, written into the cache on first use.

    The SRDF is the published one with the pairs a never-in-collision pass finds for the
    spheres added (`armkit.planning.disabled_pairs`, 5,000 samples), as a user of MoveIt's
    Setup Assistant would do after spherizing: spheres that bulge past a mesh touch neighbours
    the meshes did not (the UR5's wrist 2 and its flange's ee_link)."""
    from armkit.io.srdf import read_srdf, write_srdf
    from armkit.planning import arm_geometry
    from armkit.planning.geometry import disabled_pairs

    suffix, srdf_suffix, tip = ARMS[arm]
    out, srdf = CACHE / f"{arm}_spherized.urdf", CACHE / f"{arm}_spherized.srdf"
    if out.is_file() and srdf.is_file():
        return out, srdf, tip
    _write_spherized(data_file(suffix), out)
    robot = armkit.load_robot(out, tip=tip)
    found = disabled_pairs(robot, arm_geometry(robot), samples=5000)
    published = read_srdf(data_file(srdf_suffix)).disabled
    known = {tuple(sorted(p[:2])) for p in published}
    write_srdf(srdf, arm, list(published) + [p for p in found if tuple(sorted(p[:2]))
                                             not in known])
    return out, srdf, tip


def _write_spherized(source: Path, out: Path) -> None:
    """The URDF `source` with each link's collision elements replaced by spheres."""
    import trimesh

    from armkit.io.urdf import mesh_file

    root = ET.parse(source).getroot()
    for joint in root.findall("joint"):
        if "finger" in joint.get("name", "") and joint.get("type") == "prismatic":
            joint.set("type", "fixed")                  # fingers closed, part of the arm
            for tag in ("limit", "axis", "mimic", "dynamics"):
                for child in joint.findall(tag):
                    joint.remove(child)
    for link in root.findall("link"):
        spheres = []
        for c in link.findall("collision"):
            T = _xyz_rpy(c)
            mesh = c.find("geometry/mesh")
            if mesh is not None:
                scale = np.array([float(v) for v in mesh.get("scale", "1 1 1").split()])
                m = trimesh.load(mesh_file(mesh.get("filename"), str(source)), force="mesh")
                centres, radii = spheres_from_mesh(m.vertices * scale, m.faces, TOLERANCE)
            elif c.find("geometry/box") is not None:
                size = [float(v) for v in c.find("geometry/box").get("size").split()]
                m = trimesh.creation.box(size)
                centres, radii = spheres_from_mesh(m.vertices, m.faces, TOLERANCE)
            elif c.find("geometry/cylinder") is not None:
                cylinder = c.find("geometry/cylinder")
                m = trimesh.creation.cylinder(float(cylinder.get("radius")),
                                              float(cylinder.get("length")))
                centres, radii = spheres_from_mesh(m.vertices, m.faces, TOLERANCE)
            else:
                sphere = c.find("geometry/sphere")
                centres, radii = np.zeros((1, 3)), np.array([float(sphere.get("radius"))])
            centres = centres @ T[:3, :3].T + T[:3, 3]
            spheres.extend(zip(centres, radii))
            link.remove(c)
        for p, r in spheres:
            c = ET.SubElement(link, "collision")
            ET.SubElement(c, "origin", xyz=" ".join(f"{v:.9g}" for v in p), rpy="0 0 0")
            ET.SubElement(ET.SubElement(c, "geometry"), "sphere", radius=f"{r:.9g}")
        for visual in link.findall("visual"):
            link.remove(visual)
    CACHE.mkdir(parents=True, exist_ok=True)
    ET.ElementTree(root).write(out)


@dataclass(frozen=True)
class Problem:
    """One planning problem: a family, the arm, its obstacles, start and goal."""

    family: str
    arm: str
    index: int
    scene: Scene
    start: np.ndarray
    goal: np.ndarray


def _box(lo, hi, T) -> Box:
    """The box between corners lo, hi (structure frame), placed by T (4, 4)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return Box(hi - lo, T @ pose_from_xyz_rpy((lo + hi) / 2, [0, 0, 0]))


def _cylinder(x, y, z0, radius, height, T) -> Cylinder:
    return Cylinder(radius, height, T @ pose_from_xyz_rpy([x, y, z0 + height / 2], [0, 0, 0]))


def _shelf(plates, depth, width, thickness, T):
    """A shelf: plates at heights `plates` (their tops), side walls, a back; front at x 0."""
    top = plates[-1]
    out = [_box([0, -width / 2, z - thickness], [depth, width / 2, z], T) for z in plates]
    out += [_box([0, s * width / 2 - (thickness if s > 0 else 0), 0],
                 [depth, s * width / 2 + (thickness if s < 0 else 0), top], T) for s in (-1, 1)]
    out.append(_box([depth, -width / 2, 0], [depth + thickness, width / 2, top], T))
    return out


def family(name: str, rng) -> tuple[list, tuple, tuple]:
    """The obstacles of one problem of a family (structure moved by a random offset and yaw),
    and the start and goal regions of the tool origin (world boxes: lower and upper corners)."""
    yaw = rng.uniform(-0.2, 0.2)
    T = pose_from_xyz_rpy([rng.uniform(-0.03, 0.03), rng.uniform(-0.08, 0.08), 0.0],
                          [0, 0, yaw])

    def region(lo, hi):
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                            for z in (lo[2], hi[2])])
        world = corners @ T[:3, :3].T + T[:3, 3]
        return world.min(axis=0), world.max(axis=0)

    if name.startswith("bookshelf"):
        if name == "bookshelf_small":
            plates, depth, thick, x0 = [0.02, 0.38, 0.74, 1.1], 0.32, 0.02, 0.55
        elif name == "bookshelf_tall":
            plates, depth, thick, x0 = [0.02, 0.32, 0.62, 0.92, 1.22, 1.52], 0.3, 0.02, 0.55
        else:
            plates, depth, thick, x0 = [0.02, 0.3, 0.58, 0.86, 1.14], 0.26, 0.008, 0.58
        T = T @ pose_from_xyz_rpy([x0, 0, 0], [0, 0, 0])
        obstacles = _shelf(plates, depth, 0.8, thick, T)
        k = int(rng.integers(1, min(3, len(plates) - 1)))
        goal = region([0.08, -0.25, plates[k] + 0.06], [depth - 0.06, 0.25, plates[k + 1] - 0.1])
        start = region([-0.35, -0.4, 0.3], [-0.12, 0.4, 0.8])
        return obstacles, start, goal
    if name == "box":
        T = T @ pose_from_xyz_rpy([0.45, 0, 0], [0, 0, 0])
        table = 0.3
        obstacles = [_box([0, -0.5, table - 0.04], [0.6, 0.5, table], T)]
        lo, hi, wall, h = np.array([0.12, -0.18]), np.array([0.42, 0.18]), 0.01, 0.2
        obstacles += [_box([lo[0], lo[1], table], [hi[0], lo[1] + wall, table + h], T),
                      _box([lo[0], hi[1] - wall, table], [hi[0], hi[1], table + h], T),
                      _box([lo[0], lo[1], table], [lo[0] + wall, hi[1], table + h], T),
                      _box([hi[0] - wall, lo[1], table], [hi[0], hi[1], table + h], T)]
        goal = region([lo[0] + 0.06, lo[1] + 0.06, table + 0.08],
                      [hi[0] - 0.06, hi[1] - 0.06, table + 0.18])
        start = region([0.0, -0.5, table + 0.35], [0.5, -0.25, table + 0.6])
        return obstacles, start, goal
    if name == "table_pick":
        T = T @ pose_from_xyz_rpy([0.4, 0, 0], [0, 0, 0])
        table = 0.35
        obstacles = [_box([0, -0.5, table - 0.04], [0.5, 0.5, table], T)]
        for _ in range(6):
            x, y = rng.uniform(0.05, 0.45), rng.uniform(-0.4, 0.4)
            obstacles.append(_cylinder(x, y, table, rng.uniform(0.025, 0.04),
                                       rng.uniform(0.1, 0.2), T))
        goal = region([0.05, -0.3, table + 0.1], [0.4, 0.3, table + 0.2])
        start = region([0.0, -0.4, table + 0.4], [0.4, 0.4, table + 0.6])
        return obstacles, start, goal
    # cage: a small room of posts, plates and bars, open on the side facing the arm.
    T = T @ pose_from_xyz_rpy([0.45, 0, 0], [0, 0, 0])
    z0, z1, half = 0.25, 0.65, 0.2
    obstacles = [_box([0, -half, z0 - 0.02], [2 * half, half, z0], T),
                 _box([0, -half, z1], [2 * half, half, z1 + 0.02], T)]
    obstacles += [_cylinder(x, y, z0, 0.015, z1 - z0, T)
                  for x in (0.0, 2 * half) for y in (-half, half)]
    obstacles += [_box([0, s * half - 0.01, z0 + 0.15], [2 * half, s * half + 0.01,
                                                          z0 + 0.17], T) for s in (-1, 1)]
    obstacles += [_box([2 * half - 0.01, -half, z0 + 0.15], [2 * half + 0.01, half, z0 + 0.17],
                       T)]
    goal = region([0.12, -0.1, z0 + 0.1], [0.3, 0.1, z1 - 0.12])
    start = region([-0.3, -0.45, 0.5], [0.0, 0.45, 0.9])
    return obstacles, start, goal


def _sample_in(checker, tip_of, lo, hi, rng, count=20_000, tries=10):
    """Valid configurations whose tool origin lies in the box lo-hi."""
    robot = checker.robot
    low, high = robot.chain.sampling_limits
    for _ in range(tries):
        Q = rng.uniform(low, high, (count, robot.n))
        p = tip_of(Q)
        Q = Q[np.all((p >= lo) & (p <= hi), axis=1)]
        if len(Q):
            Q = Q[checker.valid(Q)]
            if len(Q):
                return Q
    return np.empty((0, robot.n))


def problems(arm: str, per_family: int, seed: int = 0) -> tuple[armkit.Robot, list[Problem]]:
    """The arm (its spherized URDF and SRDF) and `per_family` problems of each family."""
    urdf, srdf, tip = spherized_urdf(arm)
    robot = armkit.load_robot(urdf, tip=tip, srdf=srdf)
    model = CollisionModel(robot)
    out = []
    for f, name in enumerate(FAMILIES):
        rng = np.random.default_rng([seed, f])
        k = attempts = 0
        while k < per_family:
            attempts += 1
            if attempts > 20 * per_family:
                raise RuntimeError(f"{arm} {name}: no valid start and goal found in "
                                   f"{attempts - 1} layouts")
            obstacles, start_box, goal_box = family(name, rng)
            scene = Scene(obstacles)
            checker = CollisionChecker(model, scene)

            def tip_of(Q):
                return armkit.fk(robot, Q)[..., :3, 3]

            starts = _sample_in(checker, tip_of, *start_box, rng)
            goals = _sample_in(checker, tip_of, *goal_box, rng)
            if not (len(starts) and len(goals)):
                continue
            start, goal = starts[0], goals[0]
            if checker.edge_valid(start, goal)[0]:
                continue
            out.append(Problem(name, arm, k, scene, start, goal))
            k += 1
    return robot, out


# --- the independent checker ---------------------------------------------------------------------

class IndependentChecker:
    """Pinocchio places the spherized URDF's spheres; NumPy distances to the obstacles and
    between the SRDF's pairs (see the module's note)."""

    def __init__(self, urdf: Path, srdf: Path, n: int):
        import pinocchio as pin

        self.pin = pin
        self.model = pin.buildModelFromUrdf(str(urdf))
        if self.model.nq != n:
            raise ValueError(f"pinocchio's model has {self.model.nq} joint values, armkit's {n}")
        self.data = self.model.createData()
        root = ET.parse(urdf).getroot()
        self.frames, self.centres, self.radii, self.link = [], [], [], []
        names = []
        for link in root.findall("link"):
            spheres = [(c.find("origin").get("xyz"), c.find("geometry/sphere").get("radius"))
                       for c in link.findall("collision")]
            if not spheres:
                continue
            names.append(link.get("name"))
            for xyz, r in spheres:
                self.frames.append(self.model.getFrameId(link.get("name")))
                self.centres.append([float(v) for v in xyz.split()])
                self.radii.append(float(r))
                self.link.append(len(names) - 1)
        self.centres, self.radii = np.array(self.centres), np.array(self.radii)
        self.link = np.array(self.link)
        # Links rigidly joined (fixed joints) never move apart; the SRDF's pairs are off.
        body = {}
        for name in names:
            fid = self.model.getFrameId(name)
            body[name] = self.model.frames[fid].parentJoint
        off = {tuple(sorted((e.get("link1"), e.get("link2"))))
               for e in ET.parse(srdf).getroot().findall("disable_collisions")}
        i, j = np.triu_indices(len(self.radii), 1)
        a, b = np.array(names)[self.link[i]], np.array(names)[self.link[j]]
        keep = np.array([body[x] != body[y] and tuple(sorted((x, y))) not in off
                         for x, y in zip(a, b)], dtype=bool)
        self.pairs = np.column_stack([i[keep], j[keep]])

    def spheres(self, Q: np.ndarray) -> np.ndarray:
        """World centres of the spheres at the states Q (k, n): (k, m, 3)."""
        pin = self.pin
        out = np.empty((len(Q), len(self.radii), 3))
        frames = np.array(self.frames)
        unique = np.unique(frames)
        for s, q in enumerate(Q):
            pin.framesForwardKinematics(self.model, self.data, q)
            for f in unique:
                M = self.data.oMf[int(f)]
                k = frames == f
                out[s, k] = self.centres[k] @ M.rotation.T + M.translation
        return out

    def clearances(self, scene: Scene, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The smallest obstacle gap and self gap (m) at each state (k,)."""
        P = self.spheres(Q)
        obstacle = np.full(len(Q), np.inf)
        for o in scene:
            if isinstance(o, Box):
                x = np.abs((P - o.pose[:3, 3]) @ o.pose[:3, :3]) - o.size / 2
                d = np.linalg.norm(np.maximum(x, 0), axis=-1)
            else:
                x = (P - o.pose[:3, 3]) @ o.pose[:3, :3]
                dr = np.maximum(np.hypot(x[..., 0], x[..., 1]) - o.radius, 0)
                dz = np.maximum(np.abs(x[..., 2]) - o.length / 2, 0)
                d = np.hypot(dr, dz)
            obstacle = np.minimum(obstacle, (d - self.radii).min(axis=1))
        i, j = self.pairs[:, 0], self.pairs[:, 1]
        gaps = np.linalg.norm(P[:, i] - P[:, j], axis=-1) - self.radii[i] - self.radii[j]
        return obstacle, gaps.min(axis=1) if len(i) else np.full(len(Q), np.inf)

    def path_collides(self, scene: Scene, path: np.ndarray, step: float = 0.005) -> bool:
        """Whether some state along the path, no more than `step` rad apart on any joint,
        overlaps an obstacle or itself."""
        path = np.asarray(path, float)
        Q = [path[:1]]
        for a, b in zip(path[:-1], path[1:]):
            k = max(int(np.ceil(np.abs(b - a).max() / step)), 1)
            Q.append(a + (np.arange(1, k + 1) / k)[:, None] * (b - a))
        obstacle, own = self.clearances(scene, np.vstack(Q))
        return bool((obstacle <= 0).any() or (own <= 0).any())


def main() -> None:
    for arm in ARMS:
        robot, found = problems(arm, 3)
        model = CollisionModel(robot)
        print(f"{arm}: {len(model.geometry)} spheres on {len(set(model.geometry.names))} links, "
              f"{model.link_pairs} link pairs and {model.part_pairs} sphere pairs tested; "
              f"{len(found)} problems")
        for p in found:
            checker = CollisionChecker(model, p.scene)
            print(f"  {p.family} {p.index}: {len(p.scene)} obstacles, start clearance "
                  f"{float(checker.clearance(p.start)) * 1e3:.1f} mm, goal "
                  f"{float(checker.clearance(p.goal)) * 1e3:.1f} mm")


if __name__ == "__main__":
    main()
