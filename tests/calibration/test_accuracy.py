"""Accuracy report: the inspection-robot paper's five points are within 1 cm."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from armkit.calibration.accuracy import accuracy_report
from armkit.errors import InputError
from armkit.io.measurements import read_accuracy
from armkit.report.calibration import accuracy_figure, save_figure

EXAMPLE = Path(__file__).parents[2] / "examples" / "calibration" / "inspection_6dof_accuracy.csv"

# SPEC.md, R3: theoretical and measured end positions (mm).
COMMANDED = np.array([(200, 300, 500), (300, 450, 900), (-500, 200, 150), (-300, -400, 200),
                      (500, -500, -200)], dtype=float)
MEASURED = np.array([(202, 296, 503), (304, 455, 901), (-505, 192, 147), (-305, -403, 203),
                     (505, -497, -204)], dtype=float)


def test_paper_3_points_within_one_centimetre():
    report = accuracy_report(COMMANDED / 1000, MEASURED / 1000, tolerance=0.01)
    by_hand = np.sqrt([4 + 16 + 9, 16 + 25 + 1, 25 + 64 + 9, 25 + 9 + 9, 25 + 9 + 16]) / 1000
    assert np.allclose(report.distances, by_hand, rtol=1e-12)
    assert report.max == pytest.approx(np.sqrt(98) / 1000) and report.max < 0.01
    assert report.within is True
    assert report.mean == pytest.approx(by_hand.mean())
    assert report.rms == pytest.approx(np.sqrt(np.mean(by_hand ** 2)))
    assert np.allclose(report.bias, np.array([1, -7, 0]) / 5 / 1000, atol=1e-15)
    assert np.allclose(report.errors, (MEASURED - COMMANDED) / 1000)
    assert accuracy_report(COMMANDED / 1000, MEASURED / 1000, tolerance=0.009).within is False
    assert accuracy_report(COMMANDED / 1000, MEASURED / 1000).within is None


def test_example_file_is_the_papers_table():
    data = read_accuracy(EXAMPLE)
    assert data.units.length == "mm"
    assert np.allclose(data.commanded, COMMANDED / 1000) and np.allclose(data.measured,
                                                                         MEASURED / 1000)


def test_figure_is_written(tmp_path):
    data = read_accuracy(EXAMPLE)
    fig = accuracy_figure(accuracy_report(data.commanded, data.measured, 0.01), data.units)
    left, right = fig.axes
    assert left.get_ylabel() == "measured - commanded (mm)"
    assert right.get_ylabel() == "|measured - commanded| (mm)"
    assert any("limit 10 mm" in t.get_text() for t in right.get_legend().get_texts())
    path = save_figure(fig, tmp_path / "accuracy.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_one_point_and_bad_input():
    one = accuracy_report([[0, 0, 0]], [[0, 0, 0.003]])
    assert one.max == pytest.approx(0.003) and np.all(one.std == 0)
    with pytest.raises(InputError, match=r"measured: expected shape \(2, 3\) \(one per "
                                         r"commanded point\), found \(3, 3\)"):
        accuracy_report(np.zeros((2, 3)), np.zeros((3, 3)))
    with pytest.raises(InputError, match=r"commanded: expected shape \(\.\.\., 3\)"):
        accuracy_report(np.zeros((2, 2)), np.zeros((2, 2)))
    with pytest.raises(InputError, match="measured: expected finite numbers"):
        accuracy_report(np.zeros((1, 3)), [[np.nan, 0, 0]])
    with pytest.raises(InputError, match=r"commanded: expected shape \(m, 3\) with m >= 1"):
        accuracy_report(np.zeros((0, 3)), np.zeros((0, 3)))
    with pytest.raises(InputError, match="tolerance: expected a positive length, found -1"):
        accuracy_report(np.zeros((1, 3)), np.zeros((1, 3)), tolerance=-1)
