"""PCD files as PCL writes them: binary_compressed (LZF, checked against liblzf itself through
python-lzf), organised clouds with NaN, extra fields kept or ignored by name, counts checked
against the body exactly, and every read bounded (regular files, a size cap)."""

from __future__ import annotations

import os
import struct

import lzf
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armkit.errors import InputError, ModelFileError
from armkit.io.clouds import lzf_compress, lzf_decompress, read_cloud, write_pcd

RNG = np.random.default_rng(3)
POINTS = RNG.uniform([1.2, -0.5, -0.5], [1.8, 0.5, 0.5], (500, 3))


def pcl_compressed(path, columns: dict, width: int, height: int = 1, units="m",
                   compress=lzf.compress, pad: int = 0):
    """A binary_compressed PCD the way PCL's PCDWriter lays it out: the header, two uint32
    (compressed, uncompressed size), then LZF of the fields one after another."""
    types = {"f4": ("F", 4), "f8": ("F", 8), "u2": ("U", 2), "u1": ("U", 1), "i4": ("I", 4)}
    names = list(columns)
    spec = [types[np.asarray(columns[k]).dtype.str[1:]] for k in names]
    n = width * height
    header = (f"# .PCD v0.7 - Point Cloud Data file format\n# units: {units}\nVERSION 0.7\n"
              f"FIELDS {' '.join(names)}\nSIZE {' '.join(str(s) for _, s in spec)}\n"
              f"TYPE {' '.join(t for t, _ in spec)}\nCOUNT {' '.join('1' for _ in names)}\n"
              f"WIDTH {width}\nHEIGHT {height}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\n"
              f"DATA binary_compressed\n").encode()
    raw = b"".join(np.ascontiguousarray(columns[k]).tobytes() for k in names)
    packed = compress(raw)
    path.write_bytes(header + struct.pack("<II", len(packed), len(raw)) + packed + bytes(pad))
    return path


@given(st.binary(min_size=1, max_size=3000), st.integers(0, 6))
@settings(max_examples=60, deadline=None)
def test_lzf_round_trips_and_agrees_with_liblzf(data, repeat):
    data = data * (repeat + 1)                       # repeats give back-references
    assert lzf_decompress(lzf_compress(data), len(data)) == data
    assert lzf.decompress(lzf_compress(data), len(data) + 1) == data      # liblzf reads ours
    packed = lzf.compress(data)
    if packed is not None:                           # liblzf gives None when it cannot shrink
        assert lzf_decompress(packed, len(data)) == data                  # we read liblzf's


def test_lzf_corrupt_streams_are_refused():
    data = bytes(range(50)) * 40
    packed = lzf.compress(data)
    with pytest.raises(ValueError, match="decoded"):
        lzf_decompress(packed, len(data) - 1)
    with pytest.raises(ValueError):
        lzf_decompress(packed[:-5], len(data))
    with pytest.raises(ValueError, match="corrupt"):
        lzf_decompress(b"\xe0\xff\xff", 100)        # a reference before the start


def test_binary_compressed_as_pcl_writes_it_with_extra_fields(tmp_path):
    ring = RNG.integers(0, 64, len(POINTS)).astype("<u2")
    intensity = RNG.uniform(0, 255, len(POINTS)).astype("<f4")
    stamp = np.linspace(1.6e9, 1.6e9 + 0.1, len(POINTS))
    cols = {"x": POINTS[:, 0].astype("<f4"), "y": POINTS[:, 1].astype("<f4"),
            "z": POINTS[:, 2].astype("<f4"), "intensity": intensity, "ring": ring,
            "timestamp": stamp}
    path = pcl_compressed(tmp_path / "lidar.pcd", cols, len(POINTS), pad=1000)
    cloud = read_cloud(path)
    np.testing.assert_allclose(cloud.points, POINTS, atol=1e-6)
    assert cloud.file_units == "m" and set(cloud.fields) == {"intensity", "ring", "timestamp"}
    np.testing.assert_array_equal(cloud.fields["ring"], ring)
    np.testing.assert_array_equal(cloud.fields["timestamp"], stamp)
    assert set(read_cloud(path, fields=("ring",)).fields) == {"ring"}
    assert read_cloud(path, fields=()).fields == {}
    with pytest.raises(ModelFileError, match="fields: expected the field 'rgb' asked for"):
        read_cloud(path, fields=("rgb",))
    # Our own writer gives the same file content back.
    ours = write_pcd(tmp_path / "ours.pcd", POINTS, "mm", fields={"ring": ring})
    again = read_cloud(ours)
    np.testing.assert_allclose(again.points, POINTS, atol=1e-6)
    np.testing.assert_array_equal(again.fields["ring"], ring)
    assert b"DATA binary_compressed" in ours.read_bytes()[:400]


def test_organised_cloud_with_nan(tmp_path):
    width, height = 40, 25
    grid = np.tile(POINTS[:width], (height, 1)) + np.repeat(np.arange(height), width)[:, None] \
        * [0, 0, 0.01]
    grid[::7] = np.nan                                      # pixels without depth
    cols = {c: grid[:, i].astype("<f4") for i, c in enumerate("xyz")}
    cloud = read_cloud(pcl_compressed(tmp_path / "cam.pcd", cols, width, height))
    kept = ~np.isnan(grid).any(axis=1)
    assert cloud.organized and (cloud.width, cloud.height) == (width, height)
    assert cloud.dropped == (~kept).sum() and len(cloud.points) == kept.sum()
    np.testing.assert_array_equal(cloud.index, np.flatnonzero(kept))
    np.testing.assert_allclose(cloud.points, grid[kept], atol=1e-6)
    assert not cloud.points.flags.writeable


def bad(tmp_path, text: bytes, name="bad.pcd"):
    path = tmp_path / name
    path.write_bytes(text)
    return path


HEADER = ("# units: m\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT {count}\n"
          "WIDTH {w}\nHEIGHT {h}\nPOINTS {n}\nDATA {data}\n")


def header(w=2, h=1, n=None, count="1 1 1", data="binary"):
    return HEADER.format(w=w, h=h, n=w * h if n is None else n, count=count,
                         data=data).encode()


BODY = np.array([[1.5, 0, 0], [1.6, 0.5, 0.2]], "<f4").tobytes()


@pytest.mark.parametrize("content, message", [
    (header(n=-1) + BODY, r"POINTS: expected a whole number from 0 to 2e\+08, found -1"),
    (header(n=3) + BODY, r"POINTS: expected WIDTH x HEIGHT = 2 x 1 = 2, found 3"),
    (header(count="0 1 1") + BODY, r"COUNT of x: expected a whole number from 1 to 4096"),
    (header(count="-1 1 1") + BODY, r"COUNT of x: expected a whole number from 1"),
    (header(count="99999999999 1 1") + BODY, r"COUNT of x: expected a whole number"),
    (header(count="2 1 1") + BODY, r"field x: expected one float \(TYPE F, COUNT 1\)"),
    (header(w=10**12) + BODY, r"WIDTH: expected a whole number from 0 to 2e\+08"),
    (header() + BODY + b"\x01\x02\x03", r"DATA binary: expected 2 points of 12 bytes .* and "
                                        r"nothing after them .*found 3 bytes more"),
    (header() + BODY[:-4], r"DATA binary: expected 2 points of 12 bytes \(24 bytes\), found 20"),
    (header(data="binary_compressed") + struct.pack("<II", 10, 24) + bytes(10),
     r"DATA binary_compressed: expected an LZF stream"),
    (header(data="binary_compressed") + struct.pack("<II", 4, 2**31),
     r"expected an uncompressed size of 24 bytes"),
    (header(w=2**20, data="binary_compressed") + struct.pack("<II", 4, 12 * 2**20) + bytes(4),
     r"expected an uncompressed size that 4 compressed bytes can hold"),
    (header().replace(b"FIELDS x y z", b"FIELDS x y y") + BODY, r"FIELDS: expected each field "
                                                                r"named once, found 'y' twice"),
    (header().replace(b"WIDTH 2", b"WIDTH \xc2\xb2"), r"header line 7: expected ASCII text"),
    (header().replace(b"WIDTH 2", b"WIDTH 4_0"), r"WIDTH: expected a whole number .*'4_0'"),
    (header(data="ascii") + b"1.5 0 0\n1.6 0.5\n", r"line 12: expected 3 values"),
    (header(data="ascii") + b"1.5 0 0\n1.6 0.5 1_0\n", r"line 12: expected numbers, "
                                                       r"found '1.6 0.5 1_0'"),
    (header(data="ascii") + b"1.5 0 0\n1.6 0.5 0\n1 1 1\n", r"POINTS: expected 2 data lines, "
                                                            r"found 3"),
    (header(data="ascii") + b"1.5 0 0\n1.6 0.5 1.7e19\n", r"point 1: expected coordinates "
                                                          r"within 1e\+09 m"),
])
def test_counts_are_checked_exactly(tmp_path, content, message):
    with pytest.raises(ModelFileError, match=message):
        read_cloud(bad(tmp_path, content))


PLY = (b"ply\nformat binary_little_endian 1.0\ncomment units m\n{elements}end_header\n")


@pytest.mark.parametrize("elements, body, message", [
    (b"element vertex -5\nproperty float x\nproperty float y\nproperty float z\n", BODY,
     r"element vertex: expected a whole number from 0"),
    (b"element extra -1\nproperty float a\nelement vertex 2\nproperty float x\nproperty float y"
     b"\nproperty float z\n", BODY, r"element extra: expected a whole number from 0"),
    (b"element vertex 2\nproperty float x\nproperty float x\nproperty float y\nproperty float z"
     b"\n", BODY, r"property: expected each property named once, found 'x' twice"),
    (b"element vertex 1\nproperty float x\nproperty float y\nproperty float z\n", BODY,
     r"element counts: expected a body of 12 bytes .*found 24 bytes"),
    (b"element vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
     b"element face 1\nproperty list uchar int vertex_indices\n", BODY + b"\x03\x00",
     r"element face\[0\]: expected its list items"),
])
def test_ply_counts_are_checked_exactly(tmp_path, elements, body, message):
    with pytest.raises(ModelFileError, match=message):
        read_cloud(bad(tmp_path, PLY.replace(b"{elements}", elements) + body, "bad.ply"))


def test_ply_faces_after_the_vertices_are_accounted_for(tmp_path):
    faces = np.array([(3, 0, 1, 1)] * 4, [("n", "u1"), ("a", "<i4"), ("b", "<i4"),
                                           ("c", "<i4")]).tobytes()
    elements = (b"element vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                b"element face 4\nproperty list uchar int vertex_indices\n")
    path = bad(tmp_path, PLY.replace(b"{elements}", elements) + BODY + faces, "mesh.ply")
    assert len(read_cloud(path).points) == 2
    path.write_bytes(path.read_bytes() + b"\x00")
    with pytest.raises(ModelFileError, match="element counts"):
        read_cloud(path)


def test_reads_are_bounded(tmp_path):
    zero = tmp_path / "zero.pcd"
    os.symlink("/dev/zero", zero)
    with pytest.raises(ModelFileError, match=r"zero\.pcd: expected a regular file, found a "
                                             r"directory, device or pipe"):
        read_cloud(zero, "m")
    fifo = tmp_path / "fifo.pcd"
    os.mkfifo(fifo)
    with pytest.raises(ModelFileError, match="expected a regular file"):
        read_cloud(fifo, "m")                                  # no hang: never opened
    big = write_pcd(tmp_path / "big.pcd", POINTS, "m", data="binary")
    with pytest.raises(ModelFileError, match=r"expected a file of at most 1000 bytes"):
        read_cloud(big, max_bytes=1000)
    with pytest.raises(ModelFileError, match="expected a file name, found a NUL character"):
        read_cloud("scan\0.pcd", "m")
    with pytest.raises(InputError, match="fields: expected a sequence of field names"):
        read_cloud(big, fields="ring")


def test_the_unit_is_the_files_and_the_points_are_metres(tmp_path):
    path = write_pcd(tmp_path / "mm.pcd", POINTS, "mm")
    cloud = read_cloud(path)
    assert cloud.file_units == "mm" and not hasattr(cloud, "units")
    np.testing.assert_allclose(cloud.points, POINTS, atol=1e-6)     # metres beside "mm"
