"""Waypoint files: CSV with or without a header, JSON; NaN and inf named by line or field."""

from __future__ import annotations

import numpy as np
import pytest

import armkit
from armkit.errors import ModelFileError
from armkit.io.waypoints import read_waypoints

ROBOT = armkit.robot("inspection_6dof")


@pytest.mark.parametrize("name, text", [
    ("wp.csv", "t,q1,q2,q3,q4,q5,q6\n0,1,2,3,4,5,6\n1,6,5,4,3,2,1\n"),
    ("wp.csv", "0,1,2,3,4,5,6\n1,6,5,4,3,2,1\n"),
    ("wp.json", '{"q": [[1, 2, 3, 4, 5, 6], [6, 5, 4, 3, 2, 1]], "t": [0, 1]}'),
])
def test_the_three_forms_read_the_same(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    q, t = read_waypoints(path, ROBOT)
    np.testing.assert_array_equal(q, [[1, 2, 3, 4, 5, 6], [6, 5, 4, 3, 2, 1]])
    np.testing.assert_array_equal(t, [0, 1])


@pytest.mark.parametrize("name, text, words", [
    ("wp.csv", "q1,q2,q3,q4,q5,q6\n0,0,0,0,0,0\n1,NaN,0,0,0,0\n",
     "wp.csv: line 3, column 2: expected a valid number from -1e+09 to 1e+09, found 'NaN'"),
    ("wp.csv", "0,0,0,0,0,-inf\n", "wp.csv: line 1, column 6: expected a valid number"),
    ("wp.json", '{"q": [[0, 0, 0, 0, 0, 0]], "t": [Infinity]}',
     "wp.json: t[0]: expected a finite number from -1e+09 to 1e+09, found inf"),
])
def test_nan_and_inf_name_file_and_line(tmp_path, name, text, words):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(ModelFileError) as err:
        read_waypoints(path, ROBOT)
    assert words in str(err.value)
