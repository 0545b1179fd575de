"""Measurement CSV files: calibration measurements, pools, accuracy experiments."""

from __future__ import annotations

import re

import numpy as np
import pytest

import armkit
from armkit.errors import ModelFileError
from armkit.io.measurements import read_accuracy, read_measurements, read_pool

ROBOT = armkit.robot("water_supply")


def _csv(tmp_path, text, name="m.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_measurements_in_file_units(tmp_path):
    path = _csv(tmp_path, "# a comment\n# units: mm deg\nlift,swing1,swing2,swing3,x,y,z\n"
                          "100,10,-20,30,1000,200,700\n\n0,0,0,0,1326.5,0,525.5\n")
    data = read_measurements(path, ROBOT)
    assert np.allclose(data.q, [[0.1, np.deg2rad(10), np.deg2rad(-20), np.deg2rad(30)],
                                [0, 0, 0, 0]])
    assert np.allclose(data.measured, [[1.0, 0.2, 0.7], [1.3265, 0, 0.5255]])
    assert data.lines == (4, 6)


def test_q_columns_poses_and_robot_units_by_default(tmp_path):
    path = _csv(tmp_path, "q1,q2,q3,q4,x,y,z,roll,pitch,yaw\n0,0,0,90,1326.5,0,525.5,0,0,90\n")
    data = read_measurements(path, ROBOT)
    assert data.units == ROBOT.units and data.measured.shape == (1, 4, 4)
    assert np.allclose(data.measured[0, :3, :3], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15)
    assert np.allclose(data.q[0, 3], np.pi / 2)


def test_units_line_may_give_the_length_alone(tmp_path):
    path = _csv(tmp_path, "# units: m\nq1,q2,q3,q4,x,y,z\n0.1,10,0,0,1,0,0.6\n")
    data = read_measurements(path, ROBOT)
    assert data.units.length == "m" and data.units.angle == "deg"
    assert np.allclose(data.q[0, :2], [0.1, np.deg2rad(10)])


def test_pool_ignores_other_columns(tmp_path):
    path = _csv(tmp_path, "lift,swing1,swing2,swing3,x\n100,0,0,0,5\n200,10,0,0,5\n")
    assert np.allclose(read_pool(path, ROBOT)[:, 0], [0.1, 0.2])


@pytest.mark.parametrize("text, pattern", [
    ("", r": expected a header line naming the columns, found none"),
    ("q1,q2,q3,q4,x,y,z\n", r": expected at least one row of values under the header"),
    ("q1,q2,q3,x,y,z\n1,2,3,4,5,6\n", r"header: expected the joints of water_supply as columns "
                                      r"\(lift, swing1, swing2, swing3 or q1 \.\. q4\)"),
    ("q1,q2,q3,q4,x,y\n1,2,3,4,5,6\n", r"header: expected measured position columns x, y, z, "
                                       r"found no z"),
    ("q1,q2,q3,q4,x,y,z,roll\n1,2,3,4,5,6,7,8\n", r"header: expected all of roll, pitch, yaw "
                                                  r"or none of them, found roll"),
    ("q1,q2,q3,q4,x,y,z,w\n1,2,3,4,5,6,7,8\n", r"header: expected joint columns, x, y, z and "
                                               r"optionally roll, pitch, yaw, found unknown "
                                               r"column 'w'"),
    ("q1,q2,q3,q4,x,y,z\n1,2,3,4,5,6\n", r"line 2: expected 7 values \(one per column of the "
                                         r"header\), found 6"),
    ("q1,q2,q3,q4,x,y,z\n1,2,3,4,5,six,7\n", r"line 2, column y: expected a valid number "
                                             r"from -1e\+09 to 1e\+09, found 'six'"),
    ("q1,q2,q3,q4,x,y,z\n1,2,3,4,5,nan,7\n", r"line 2, column y: expected a valid number"),
    ("q1,q2,q3,q4,x,y,z\n1,2,3,4,5,1e308,7\n", r"line 2, column y: expected a number "
                                               r"from -1e\+09 to 1e\+09, found 1e\+308"),
    ("# units: mm deg\n# units: m deg\nq1,q2,q3,q4,x,y,z\n1,2,3,4,5,6,7\n",
     r"line 2: expected one units line, before the header, found another"),
    ("# units: inch\nq1,q2,q3,q4,x,y,z\n1,2,3,4,5,6,7\n", r"line 1: expected units as 'LENGTH "
                                                          r"\[ANGLE\]'.*found 'inch'"),
    ("q1,q1,q3,q4,x,y,z\n1,2,3,4,5,6,7\n", r"line 1: expected distinct column names, found "
                                           r"'q1' twice"),
])
def test_bad_measurement_files(tmp_path, text, pattern):
    path = _csv(tmp_path, text)
    with pytest.raises(ModelFileError) as err:
        read_measurements(path, ROBOT)
    message = str(err.value)
    assert message.startswith(str(path)) and re.search(pattern, message), message


def test_accuracy_files(tmp_path):
    path = _csv(tmp_path, "# units: mm\ncommanded_x,commanded_y,commanded_z,measured_x,"
                          "measured_y,measured_z\n1,2,3,1,2,4\n")
    data = read_accuracy(path)
    assert np.allclose(data.commanded, [[0.001, 0.002, 0.003]])
    assert np.allclose(data.measured, [[0.001, 0.002, 0.004]])
    path = _csv(tmp_path, "commanded_x,commanded_y,commanded_z,measured_x,measured_y,"
                          "measured_z\n1,2,3,1,2,4\n")
    with pytest.raises(ModelFileError, match=r"units: expected a '# units: mm' \(or m\) line "
                                             r"before the header, found none"):
        read_accuracy(path)
    path = _csv(tmp_path, "# units: mm\nx,y,z\n1,2,3\n")
    with pytest.raises(ModelFileError, match=r"header: expected the columns commanded_x, .*"
                                             r"found x, y, z"):
        read_accuracy(path)
    path = tmp_path / "latin1.csv"
    path.write_bytes("# units: mm\n# caf\xe9\n".encode("latin-1"))
    with pytest.raises(ModelFileError, match="expected a UTF-8 text file"):
        read_accuracy(path)
