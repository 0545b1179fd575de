"""Cloud readers: round trips through files written here by hand (PCD ascii/binary, PLY
ascii/binary, CSV, XYZ, npy), units, NaN/inf, and every bad file with one precise error."""

from __future__ import annotations

import numpy as np
import pytest

from armkit.errors import InputError, ModelFileError
from armkit.io.clouds import read_cloud, write_pcd

RNG = np.random.default_rng(0)
# A scene about a metre across, 1.5 m ahead, in metres.
POINTS = RNG.uniform([1.2, -0.5, -0.5], [1.8, 0.5, 0.5], (200, 3))


def pcd_header(n, data, fields="x y z", size="4 4 4", type_="F F F", count="1 1 1", units="mm"):
    unit = f"# units: {units}\n" if units else ""
    return (f"# .PCD v0.7 - Point Cloud Data file format\n{unit}VERSION 0.7\nFIELDS {fields}\n"
            f"SIZE {size}\nTYPE {type_}\nCOUNT {count}\nWIDTH {n}\nHEIGHT 1\n"
            f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {data}\n").encode()


def write(tmp_path, name, content: bytes | str):
    path = tmp_path / name
    path.write_bytes(content.encode() if isinstance(content, str) else content)
    return path


def test_pcd_ascii_in_millimetres(tmp_path):
    rows = "\n".join(" ".join(f"{v:.6f}" for v in row) for row in POINTS * 1000)
    path = write(tmp_path, "a.pcd", pcd_header(len(POINTS), "ascii") + rows.encode())
    cloud = read_cloud(path)
    assert cloud.file_units == "mm" and cloud.dropped == 0 and cloud.path == str(path)
    np.testing.assert_allclose(cloud.points, POINTS, atol=1e-9)


def test_pcd_binary_with_extra_fields(tmp_path):
    # x y z intensity (float32) and ring (uint16), as LiDAR drivers write.
    rec = np.zeros(len(POINTS), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"),
                                       ("intensity", "<f4"), ("ring", "<u2")])
    for i, c in enumerate("xyz"):
        rec[c] = POINTS[:, i]
    rec["intensity"], rec["ring"] = 7.0, 3
    header = pcd_header(len(POINTS), "binary", "x y z intensity ring", "4 4 4 4 2",
                        "F F F F U", "1 1 1 1 1", units=None)
    path = write(tmp_path, "b.pcd", header + rec.tobytes())
    cloud = read_cloud(path, "m")
    np.testing.assert_allclose(cloud.points, POINTS.astype(np.float32), atol=0)


def test_write_pcd_round_trip(tmp_path):
    for data in ("binary_compressed", "binary", "ascii"):
        path = write_pcd(tmp_path / f"w{data}.pcd", POINTS, "mm", data=data)
        cloud = read_cloud(path)
        assert cloud.file_units == "mm"
        np.testing.assert_allclose(cloud.points, POINTS, atol=1e-6)


def ply_header(fmt, n, extra="", units="m"):
    unit = f"comment units {units}\n" if units else ""
    return (f"ply\nformat {fmt} 1.0\ncomment written by hand\n{unit}element vertex {n}\n"
            f"property float x\nproperty float y\nproperty float z\nproperty uchar red\n"
            f"{extra}end_header\n").encode()


def test_ply_ascii_with_faces(tmp_path):
    rows = "\n".join(f"{x:.7f} {y:.7f} {z:.7f} 200" for x, y, z in POINTS)
    faces = "\n3 0 1 2\n3 1 2 3\n"
    header = ply_header("ascii", len(POINTS),
                        "element face 2\nproperty list uchar int vertex_indices\n")
    cloud = read_cloud(write(tmp_path, "a.ply", header + (rows + faces).encode()))
    assert cloud.file_units == "m"
    np.testing.assert_allclose(cloud.points, POINTS, atol=1e-6)


@pytest.mark.parametrize("fmt, endian", [("binary_little_endian", "<"),
                                         ("binary_big_endian", ">")])
def test_ply_binary(tmp_path, fmt, endian):
    rec = np.zeros(len(POINTS), dtype=[("x", endian + "f4"), ("y", endian + "f4"),
                                       ("z", endian + "f4"), ("red", "u1")])
    for i, c in enumerate("xyz"):
        rec[c] = POINTS[:, i] * 1000
    path = write(tmp_path, "b.ply", ply_header(fmt, len(POINTS), units=None) + rec.tobytes())
    cloud = read_cloud(path, units="mm")
    np.testing.assert_allclose(cloud.points, POINTS, atol=1e-6)


def test_csv_with_header_xyz_and_npy(tmp_path):
    csv = "# units: m\nintensity,x,y,z\n" + "\n".join(
        f"1,{x!r},{y!r},{z!r}" for x, y, z in POINTS.tolist())
    np.testing.assert_array_equal(read_cloud(write(tmp_path, "a.csv", csv)).points, POINTS)
    xyz = "\n".join(f"{x!r} {y!r} {z!r}" for x, y, z in (POINTS * 1000).tolist())
    np.testing.assert_allclose(read_cloud(write(tmp_path, "a.xyz", xyz), "mm").points, POINTS,
                               rtol=1e-15)
    np.save(tmp_path / "a.npy", POINTS)
    np.testing.assert_array_equal(read_cloud(tmp_path / "a.npy", "m").points, POINTS)
    rec = np.zeros(len(POINTS), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8"), ("i", "f4")])
    rec["x"], rec["y"], rec["z"] = POINTS.T
    np.save(tmp_path / "s.npy", rec)
    np.testing.assert_array_equal(read_cloud(tmp_path / "s.npy", "m").points, POINTS)


def test_nan_and_inf_dropped_and_counted_or_refused(tmp_path):
    p = POINTS.copy()
    p[[3, 10, 11]] = [np.nan, 0, 0], [np.inf, 1, 1], [0, -np.inf, 0]
    text = "# units: m\n" + "\n".join(f"{x} {y} {z}" for x, y, z in p[3:].tolist())
    cloud = read_cloud(write(tmp_path, "n.xyz", text))           # 'nan' on the first line
    assert cloud.dropped == 3 and len(cloud.points) == len(p) - 6
    np.save(tmp_path / "n.npy", p)
    cloud = read_cloud(tmp_path / "n.npy", "m")
    assert cloud.dropped == 3 and len(cloud.points) == len(p) - 3
    with pytest.raises(ModelFileError, match=r"n\.npy: points: expected finite coordinates, "
                                             r"found 3 point\(s\) with NaN or inf, the first "
                                             r"at index 3"):
        read_cloud(tmp_path / "n.npy", "m", nonfinite="refuse")
    np.save(tmp_path / "all.npy", np.full((5, 3), np.nan))
    with pytest.raises(ModelFileError, match="expected at least one finite point, found none"):
        read_cloud(tmp_path / "all.npy", "m")


def test_units_wrong_way_round_are_caught(tmp_path):
    np.save(tmp_path / "m.npy", POINTS)                    # metres
    with pytest.raises(ModelFileError, match=r"m\.npy: points: expected a scene at least 5 cm "
                                             r"across .* found 1\.\d+ mm across"):
        read_cloud(tmp_path / "m.npy", "mm")
    np.save(tmp_path / "mm.npy", POINTS * 1000)            # millimetres
    with pytest.raises(ModelFileError, match=r"mm\.npy: points: expected points within 1 km "
                                             r"of the sensor .* found a median range of 1\d\d\d"):
        read_cloud(tmp_path / "mm.npy", "m")


def test_units_missing_or_contradicting(tmp_path):
    np.save(tmp_path / "a.npy", POINTS)
    with pytest.raises(ModelFileError, match=r"a\.npy: units: expected a length unit, m or mm, "
                                             r"declared in the file or given .*found none"):
        read_cloud(tmp_path / "a.npy")
    path = write_pcd(tmp_path / "a.pcd", POINTS, "mm")
    with pytest.raises(ModelFileError, match=r"a\.pcd: units: expected m as given by the "
                                             r"caller, found the file declares mm"):
        read_cloud(path, "m")
    with pytest.raises(InputError, match="units: expected m or mm, found 'cm'"):
        read_cloud(path, "cm")
    with pytest.raises(InputError, match="nonfinite: expected 'drop' or 'refuse'"):
        read_cloud(path, nonfinite="keep")


PNG = b"\x89PNG\r\n\x1a\n" + bytes(100)


@pytest.mark.parametrize("name, content, message", [
    ("e.pcd", pcd_header(0, "ascii"), r"e\.pcd: points: expected at least one point, found none"),
    ("e.csv", "# units: m\nx,y,z\n", r"e\.csv: points: expected at least one point"),
    ("p.pcd", PNG, r"p\.pcd: expected a PCD file \(starting with #, VERSION or FIELDS\), "
                   r"found b'\\x89PNG"),
    ("p.ply", PNG, r"p\.ply: expected a PLY file \(starting with ply\)"),
    ("z.pcd", b"", r"z\.pcd: expected a PCD file .*found an empty file"),
    ("p.npy", PNG, r"p\.npy: expected a NumPy \.npy file"),
    ("p.csv", PNG, r"p\.csv: expected a text file of x y z rows, found binary data"),
    ("c.pcd", pcd_header(3, "binary_compressed") + bytes(20),
     r"c\.pcd: DATA binary_compressed: expected an uncompressed size of 36 bytes .*found 0"),
    ("t.pcd", pcd_header(100, "binary") + bytes(40),
     r"t\.pcd: DATA binary: expected 100 points of 12 bytes \(1,200 bytes\), found 40 bytes"),
    ("f.pcd", pcd_header(1, "ascii", "x y intensity") + b"1 2 3\n",
     r"f\.pcd: FIELDS: expected fields x, y and z, found 'x y intensity'"),
    ("s.pcd", pcd_header(1, "ascii", size="4 4") + b"1 2 3\n",
     r"s\.pcd: SIZE: expected 3 entries, one per field, found 2"),
    ("n.pcd", pcd_header(3, "ascii") + b"1000 0 0\n1000 1 1\n1000 2\n",
     r"n\.pcd: line 15: expected 3 values \(FIELDS, COUNT\), found 2"),
    ("l.pcd", pcd_header(3, "ascii") + b"1000 0 0\n1000 1 1\n",
     r"l\.pcd: POINTS: expected 3 data lines, found 2"),
    ("w.csv", "# units: m\nx,y,z\n1,2,3\n1,two,3\n", r"w\.csv: line 4: expected numbers, "
                                                    r"found '1 two 3'"),
    ("h.csv", "# units: m\na,b,c\n1,2,3\n", r"h\.csv: line 2: expected a header naming "
                                            r"columns x, y and z, found 'a,b,c'"),
    ("k.csv", "# units: m\n1,2\n3,4\n", r"k\.csv: line 2: expected at least 3 values per line"),
    ("v.ply", b"ply\nformat ascii 1.0\ncomment units m\nelement face 1\nproperty list uchar "
              b"int i\nend_header\n3 0 1 2\n",
     r"v\.ply: element vertex: expected a vertex element, found none"),
    ("b.ply", ply_header("binary_little_endian", 10) + bytes(13),
     r"b\.ply: element vertex: expected 10 items of 13 bytes \(130 bytes\), found 13 bytes"),
    ("f.ply", ply_header("binary_middle_endian", 1), r"f\.ply: format: expected ascii, "
                                                     r"binary_little_endian or binary_big_endian"),
    ("u.pcd", pcd_header(1, "ascii").replace(b"# units: mm\n", b"# units: mm\n# units: m\n")
     + b"1000 0 0\n", r"u\.pcd: units: expected one declared unit, found m and mm"),
    ("cloud.las", b"LASF", r"cloud\.las: expected a cloud file \(\.pcd, \.ply, \.csv, \.xyz, "
                           r"\.txt, \.npy\), found the suffix '\.las'"),
])
def test_bad_files_are_one_precise_error(tmp_path, name, content, message):
    path = write(tmp_path, name, content)
    with pytest.raises(ModelFileError, match=message):
        read_cloud(path)


def test_pickled_npy_missing_file_and_wrong_shape(tmp_path):
    np.save(tmp_path / "o.npy", np.array([{"x": 1}], dtype=object), allow_pickle=True)
    with pytest.raises(ModelFileError, match=r"o\.npy: expected a NumPy \.npy array without "
                                             r"Python objects"):
        read_cloud(tmp_path / "o.npy", "m")
    with pytest.raises(ModelFileError, match=r"missing\.pcd: expected a readable file"):
        read_cloud(tmp_path / "missing.pcd", "m")
    np.save(tmp_path / "w.npy", np.zeros((10, 2)))
    with pytest.raises(ModelFileError, match=r"w\.npy: array: expected real numbers of shape "
                                             r"\(N, 3\)"):
        read_cloud(tmp_path / "w.npy", "m")
