"""Map files: written and read back bit for bit; every damaged or hostile file is one
ModelFileError naming the file and the field, never another exception."""

from __future__ import annotations

import io
import json
import zipfile

import numpy as np
import pytest

import armkit
from armkit.errors import ModelFileError
from armkit.io.reach_maps import read_map, save_map
from armkit.reach import reach_map

ARM = armkit.robot("water_supply")


@pytest.fixture(scope="module")
def small_map():
    return reach_map(ARM, 0.2, 12, chunk=64)


@pytest.fixture()
def map_file(tmp_path, small_map):
    return save_map(small_map, tmp_path / "water_supply_reach.npz")


def fields_of(path) -> dict:
    with np.load(path, allow_pickle=False) as data:
        return {k: data[k] for k in data.files}


def write_fields(path, fields: dict) -> None:
    with open(path, "wb") as stream:
        np.savez(stream, **fields)


def test_a_map_reads_back_bit_for_bit(map_file, small_map):
    m = read_map(map_file, ARM)
    for name in ("voxels", "count", "reached", "manipulability"):
        assert np.array_equal(getattr(m, name), getattr(small_map, name))
    np.testing.assert_array_equal(m.orientations.rotations, small_map.orientations.rotations)
    np.testing.assert_array_equal(m.orientations.mask, small_map.orientations.mask)
    assert m.resolution == small_map.resolution and m.settings == small_map.settings
    assert m.orientations.description == small_map.orientations.description
    assert np.array_equal(m.index_at(small_map.centers), small_map.index)
    # The file says what it is: numpy reads it without pickles.
    fields = fields_of(map_file)
    assert str(fields["format"]) == "armkit reach map 1" and str(fields["robot"]) == ARM.name
    assert json.loads(str(fields["settings"]))["method"] == "analytic"


def test_a_map_of_another_robot_is_refused(map_file):
    with pytest.raises(ModelFileError, match="robot: expected a map of ur5"):
        read_map(map_file, armkit.robot("ur5"))


def mutations(fields: dict):
    """(what, fields) pairs, each one field made wrong."""
    V = len(fields["voxels"])
    swapped = fields["voxels"].copy()
    swapped[[0, 1]] = swapped[[1, 0]]
    bits = fields["reached"].copy()
    bits[0, 0] ^= 1
    nan = fields["rotations"].copy()
    nan[0, 0, 0] = np.nan
    skew = fields["rotations"].copy()
    skew[1, 0, 1] += 0.1
    mirror = fields["rotations"].copy()
    mirror[0, :, 0] *= -1
    yield from [
        ("format", {"format": np.array("some other format")}),
        ("resolution", {"resolution": np.float64(-0.2)}),
        ("resolution", {"resolution": np.float64(np.inf)}),
        ("resolution", {"resolution": np.array([0.2, 0.2])}),
        ("voxels", {"voxels": fields["voxels"][:, :2]}),
        ("voxels", {"voxels": fields["voxels"].astype(float)}),
        ("voxels", {"voxels": swapped}),
        ("voxels", {"voxels": fields["voxels"] + 2**40}),
        ("count", {"count": fields["count"][:-1]}),
        ("count", {"count": fields["count"] + 1}),
        ("count", {"reached": bits}),
        ("reached", {"reached": fields["reached"].astype(np.int64)}),
        ("manipulability", {"manipulability": -fields["manipulability"] - 1}),
        ("manipulability", {"manipulability": np.full(V, np.nan)}),
        ("rotations", {"rotations": nan}),
        ("rotations", {"rotations": skew}),
        ("rotations", {"rotations": mirror}),
        ("rotations", {"rotations": fields["rotations"][:, :2]}),
        ("mask", {"mask": np.zeros(6, bool)}),
        ("mask", {"mask": np.ones(5, bool)}),
        ("frame", {"frame": np.array("world")}),
        ("settings", {"settings": np.array("{not json")}),
        ("settings", {"settings": np.array("[1, 2]")}),
        ("robot", {"robot_key": np.array("0" * 64)}),
        ("description", {"description": np.array([1, 2, 3])}),
    ]


def test_each_wrong_field_is_named(tmp_path, map_file):
    good = fields_of(map_file)
    for i, (field, change) in enumerate(mutations(good)):
        bad = tmp_path / f"bad{i}.npz"
        write_fields(bad, good | change)
        with pytest.raises(ModelFileError) as caught:
            read_map(bad, ARM)
        assert str(caught.value).startswith(f"{bad}: {field}: expected"), (field, caught.value)


def test_missing_fields_pickles_and_lies_are_refused(tmp_path, map_file):
    good = fields_of(map_file)
    missing = tmp_path / "missing.npz"
    write_fields(missing, {k: v for k, v in good.items() if k != "count"})
    with pytest.raises(ModelFileError, match="count: expected a field of the map"):
        read_map(missing, ARM)
    pickled = tmp_path / "pickled.npz"
    with open(pickled, "wb") as stream:
        np.savez(stream, **(good | {"settings": np.array([{"a": 1}], dtype=object)}))
    with pytest.raises(ModelFileError, match="settings: expected numbers or text, found dtype"):
        read_map(pickled, ARM)
    # A member whose header claims a terabyte array in a few bytes.
    liar = tmp_path / "liar.npz"
    with zipfile.ZipFile(liar, "w") as archive:
        for name, value in good.items():
            buffer = io.BytesIO()
            if name == "voxels":
                header = {"descr": "<i8", "fortran_order": False, "shape": (2**37, 3)}
                np.lib.format.write_array_header_1_0(buffer, header)
            else:
                np.lib.format.write_array(buffer, np.asarray(value))
            archive.writestr(f"{name}.npy", buffer.getvalue())
    with pytest.raises(ModelFileError, match="voxels: expected an array as large as its header"):
        read_map(liar, ARM)


@pytest.mark.parametrize("content", [b"", b"PK\x03\x04garbage", b"\x00" * 100,
                                     b"not a zip file at all"])
def test_files_that_are_not_maps(tmp_path, content):
    path = tmp_path / "map.npz"
    path.write_bytes(content)
    with pytest.raises(ModelFileError, match=f"{path}: expected a reachability map"):
        read_map(path, ARM)
    with pytest.raises(ModelFileError, match="expected a readable map file"):
        read_map(tmp_path / "nowhere.npz", ARM)


def fuzz(path, data: bytes, count: int, seed: int) -> None:
    """Flip, cut and repeat bytes of a good file: each mutant loads or says why, as a
    ModelFileError."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        mutant = bytearray(data)
        kind = rng.integers(3)
        if kind == 0:
            for at in rng.integers(0, len(mutant), rng.integers(1, 8)):
                mutant[at] = rng.integers(256)
        elif kind == 1:
            mutant = mutant[:rng.integers(0, len(mutant))]
        else:
            a, b = sorted(rng.integers(0, len(mutant), 2))
            mutant = mutant[:b] + mutant[a:]
        path.write_bytes(bytes(mutant))
        try:
            read_map(path, ARM)
        except ModelFileError:
            pass


def test_mutated_files_load_or_say_why(tmp_path, map_file):
    fuzz(tmp_path / "mutant.npz", map_file.read_bytes(), 200, seed=3)


@pytest.mark.slow
def test_many_mutated_files_load_or_say_why(tmp_path, map_file):
    fuzz(tmp_path / "mutant.npz", map_file.read_bytes(), 3000, seed=4)
