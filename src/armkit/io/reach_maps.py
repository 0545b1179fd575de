"""Reachability map files (.npz) and the folder of finished chunks that lets a map resume.

A map file is a NumPy ``.npz`` archive (`numpy.savez_compressed`, no pickles), SI units:

==================  ================  ==========================================================
name                dtype, shape      what
==================  ================  ==========================================================
``format``          str               ``"armkit reach map 1"``
``armkit``          str               the armkit version that made it
``robot``           str               the robot's name
``robot_key``       str               hash of its chain and limits (`armkit.reach.maps.robot_key`)
``resolution``      float64, ()       voxel edge h (m)
``voxels``          int64, (V, 3)     voxel indices, lexicographic: cube [i h, (i + 1) h) ...
``count``           int64, (V,)       orientations reached per voxel
``reached``         uint8, (V, B)     which: bit k of row v (little-endian bits), B = ceil(K/8)
``manipulability``  float64, (V,)     best Yoshikawa manipulability per voxel (0: none reached)
``rotations``       float64, (K,3,3)  the orientations, in the base or the voxel's radial frame
``mask``            bool, (6,)        the IK task (x, y, z, rx, ry, rz)
``frame``           str               ``"base"`` or ``"radial"``
``kind``            str               how the orientations were made (sphere, axis, ...)
``description``     str               the orientations in words
``settings``        str               JSON: method, restarts, seed, samples, chunk, ...
==================  ================  ==========================================================

`read_map` checks every field (kinds, shapes, ranges, sorted voxels, counts that match the
bits, rotation matrices) and names the file and the field for any mistake; a map is read only
with the robot it was made for.
"""

from __future__ import annotations

import json
import os
import shutil
import tokenize
import zipfile
import zlib
from pathlib import Path

import numpy as np

from armkit.errors import ModelFileError
from armkit.model.chain import frozen_array
from armkit.model.robot import Robot
from armkit.reach.maps import MapChunk, ReachMap, robot_key, voxel_keys
from armkit.reach.orientations import Orientations

FORMAT = "armkit reach map 1"
MAX_BYTES = 2**31          # a map's arrays, uncompressed, at most (the file's own claim)
_FIELDS = ("format", "armkit", "robot", "robot_key", "resolution", "voxels", "count", "reached",
           "manipulability", "rotations", "mask", "frame", "kind", "description", "settings")


def save_map(reach_map: ReachMap, path: str | Path) -> Path:
    """Write a map as a compressed .npz file (see the module's note); returns the path."""
    m, o = reach_map, reach_map.orientations
    path = Path(path)
    fields = {"format": FORMAT, "armkit": str(m.settings.get("armkit", "")),
              "robot": m.robot.name, "robot_key": robot_key(m.robot),
              "resolution": np.float64(m.resolution), "voxels": m.voxels, "count": m.count,
              "reached": m.reached, "manipulability": m.manipulability,
              "rotations": o.rotations, "mask": o.mask, "frame": o.frame, "kind": o.kind,
              "description": o.description, "settings": json.dumps(m.settings)}
    with path.open("wb") as stream:
        np.savez_compressed(stream, **{k: np.asarray(v) for k, v in fields.items()})
    return path


def read_map(path: str | Path, robot: Robot) -> ReachMap:
    """The map in a .npz file, for `robot`.

    Raises
    ------
    ModelFileError
        Naming the file and the field: not an npz archive, a field missing or of the wrong
        kind or shape, values out of range, or a map of another robot.
    """
    path = str(path)
    arrays = _arrays(path)
    text = {name: _text(path, arrays, name) for name in ("format", "armkit", "robot", "robot_key",
                                                         "frame", "kind", "description",
                                                         "settings")}
    if text["format"] != FORMAT:
        raise ModelFileError(path, "format", repr(FORMAT), repr(text["format"][:60]))
    if text["robot_key"] != robot_key(robot):
        raise ModelFileError(path, "robot", f"a map of {robot.name} (its chain and limits)",
                             f"a map of {text['robot'][:60]!r}"
                             + (" with other kinematics or limits"
                                if text["robot"] == robot.name else ""))
    h = _array(path, arrays, "resolution", "f", ())
    if not (np.isfinite(h) and 0 < h <= 1e3):
        raise ModelFileError(path, "resolution", "a voxel edge above 0 and at most 1000 m",
                             f"{float(h):g}")
    voxels = _array(path, arrays, "voxels", "i", (None, 3))
    V = len(voxels)
    if V and np.abs(voxels).max() >= 2**19:
        raise ModelFileError(path, "voxels", "indices below 2^19 in magnitude",
                             f"{int(np.abs(voxels).max())}")
    keys = voxel_keys(voxels.astype(np.int64))
    if V > 1 and not (np.diff(keys) > 0).all():
        raise ModelFileError(path, "voxels", "distinct voxels in lexicographic order",
                             "voxels out of order or repeated")
    rotations = _array(path, arrays, "rotations", "f", (None, 3, 3))
    K = len(rotations)
    if not 1 <= K <= 100_000 or not np.isfinite(rotations).all():
        raise ModelFileError(path, "rotations", "1 .. 100000 finite rotation matrices",
                             f"{K} of them" if np.isfinite(rotations).all() else "NaN or inf")
    off = np.abs(np.einsum("kji,kjl->kil", rotations, rotations) - np.eye(3)).max()
    if off > 1e-6 or (np.linalg.det(rotations) <= 0).any():
        raise ModelFileError(path, "rotations", "rotation matrices",
                             f"one {off:.3g} off orthonormal or a reflection")
    mask = _array(path, arrays, "mask", "b", (6,))
    if not mask[:3].all():
        raise ModelFileError(path, "mask", "a task with the three positions",
                             str(mask.astype(int).tolist()))
    if text["frame"] not in ("base", "radial"):
        raise ModelFileError(path, "frame", "'base' or 'radial'", repr(text["frame"][:60]))
    count = _array(path, arrays, "count", "i", (V,))
    reached = _array(path, arrays, "reached", "u", (V, -(-K // 8)))
    if reached.dtype != np.uint8:
        raise ModelFileError(path, "reached", "uint8 bits", str(reached.dtype))
    bits = np.unpackbits(reached, axis=1, bitorder="little")
    if bits[:, K:].any() or not np.array_equal(bits.sum(axis=1), count):
        raise ModelFileError(path, "count", "the number of bits set in each row of reached",
                             "other counts")
    manipulability = _array(path, arrays, "manipulability", "f", (V,))
    if not (np.isfinite(manipulability).all() and (manipulability >= 0).all()):
        raise ModelFileError(path, "manipulability", "finite values >= 0",
                             "NaN, inf or a negative value")
    try:
        settings = json.loads(text["settings"])
    except ValueError:
        settings = None
    if not isinstance(settings, dict):
        raise ModelFileError(path, "settings", "a JSON object", repr(text["settings"][:60]))
    orientations = Orientations(frozen_array(rotations), frozen_array(mask, bool),
                                text["frame"], text["kind"], text["description"])
    fields = {"voxels": voxels.astype(np.int64), "count": count.astype(np.int64),
              "reached": reached, "manipulability": manipulability.astype(float)}
    for a in fields.values():
        a.setflags(write=False)
    return ReachMap(robot, float(h), orientations=orientations, settings=settings, **fields)


def _arrays(path: str) -> dict[str, np.ndarray]:
    """The archive's arrays, each member's header checked against its size before it is
    read: a member cannot claim more than it holds, nor all of them more than MAX_BYTES."""
    try:
        with zipfile.ZipFile(path) as archive:
            members = {info.filename: info for info in archive.infolist()}
            total = sum(info.file_size for info in members.values())
            if total > MAX_BYTES:
                raise ModelFileError(path, "", f"a map of at most {MAX_BYTES} bytes of arrays",
                                     f"{total} bytes")
            arrays = {}
            for name in _FIELDS:
                info = members.get(f"{name}.npy")
                if info is None:
                    raise ModelFileError(path, name, "a field of the map (see "
                                         "armkit.io.reach_maps)", "nothing")
                with archive.open(info) as stream:
                    version = np.lib.format.read_magic(stream)
                    header = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                              else np.lib.format.read_array_header_2_0)
                    shape, _, dtype = header(stream)
                    if dtype.hasobject or dtype.kind not in "biufU":
                        raise ModelFileError(path, name, "numbers or text", f"dtype {dtype}")
                    if int(np.prod(shape, dtype=np.float64)) * dtype.itemsize > info.file_size:
                        raise ModelFileError(path, name, "an array as large as its header "
                                             "says", f"shape {shape} in {info.file_size} bytes")
                with archive.open(info) as stream:
                    arrays[name] = np.lib.format.read_array(stream, allow_pickle=False)
            return arrays
    except ModelFileError:
        raise
    except (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, OSError, ValueError,
            NotImplementedError, KeyError, RuntimeError, TypeError, SyntaxError,
            tokenize.TokenError, zlib.error) as err:
        # What zipfile, zlib and numpy's header parser raise on damaged bytes.
        if isinstance(err, OSError) and not isinstance(err, zipfile.BadZipFile) \
                and not Path(path).is_file():
            raise ModelFileError(path, "", "a readable map file (.npz)",
                                 err.strerror or str(err)) from None
        raise ModelFileError(path, "", "a reachability map (.npz)",
                             f"{type(err).__name__}: {str(err)[:80]}") from None


def _array(path: str, arrays: dict, name: str, kinds: str, shape: tuple) -> np.ndarray:
    """Field `name`, of a dtype kind in `kinds` (b, i, u, f), of `shape` (None: any)."""
    a = arrays[name]
    kind_ok = a.dtype.kind in kinds or (kinds == "i" and a.dtype.kind == "u")
    if not kind_ok:
        raise ModelFileError(path, name, {"b": "booleans", "i": "integers", "u": "integers",
                                          "f": "floats"}[kinds[0]], f"dtype {a.dtype}")
    if a.ndim != len(shape) or any(s is not None and s != t for s, t in zip(shape, a.shape)):
        wanted = "(" + ", ".join("n" if s is None else str(s) for s in shape) + \
                 ("," if len(shape) == 1 else "") + ")"
        raise ModelFileError(path, name, f"shape {wanted}", f"{a.shape}")
    return a


def _text(path: str, arrays: dict, name: str) -> str:
    a = arrays[name]
    if a.dtype.kind != "U" or a.ndim != 0:
        raise ModelFileError(path, name, "a text", f"dtype {a.dtype}, shape {a.shape}")
    return str(a)


class ChunkFolder:
    """A map's finished chunks in a folder, one ``chunk-NNNNNN.npz`` each, beside
    ``settings.txt`` (the settings' hash): `armkit.reach_map`'s `checkpoint`.

    A run whose settings match the folder's takes its chunks from it and solves only the
    rest; a run of other settings empties the folder first. A chunk is written to a temporary
    file and renamed into place, so an interrupted run leaves whole chunks only; a chunk file
    that does not read back as the chunk it should be is solved again.
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.resumed = 0

    def start(self, key: str, sizes: list[int], orientations: int) -> dict[int, MapChunk]:
        try:
            self.path.mkdir(parents=True, exist_ok=True)
            stamp = self.path / "settings.txt"
            same = stamp.is_file() and stamp.read_text(encoding="utf-8").strip() == key
            if not same:
                self.clear()
                self.path.mkdir(parents=True, exist_ok=True)
                stamp.write_text(key + "\n", encoding="utf-8")
                return {}
        except OSError as err:
            raise ModelFileError(str(self.path), "", "a folder armkit can write chunks to",
                                 err.strerror or str(err)) from None
        found = {}
        for i, size in enumerate(sizes):
            chunk = self._read(self.path / f"chunk-{i:06d}.npz", size, orientations)
            if chunk is not None:
                found[i] = chunk
        self.resumed = len(found)
        return found

    def save(self, index: int, chunk: MapChunk) -> None:
        final = self.path / f"chunk-{index:06d}.npz"
        temporary = final.with_suffix(".tmp")
        with temporary.open("wb") as stream:
            np.savez(stream, count=chunk.count, reached=chunk.reached,
                     manipulability=chunk.manipulability)
        os.replace(temporary, final)

    def clear(self) -> None:
        """Remove the folder and its chunks (when the map is written, or settings change)."""
        if self.path.is_dir():
            shutil.rmtree(self.path)

    @staticmethod
    def _read(path: Path, size: int, orientations: int) -> MapChunk | None:
        if not path.is_file():
            return None
        try:
            with np.load(path, allow_pickle=False) as data:
                count, reached, best = (data["count"], data["reached"], data["manipulability"])
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, zlib.error):
            return None
        width = -(-orientations // 8)
        if (count.shape != (size,) or reached.shape != (size, width) or best.shape != (size,)
                or reached.dtype != np.uint8 or count.dtype.kind != "i"
                or best.dtype.kind != "f"):
            return None
        return MapChunk(count, reached, best)
