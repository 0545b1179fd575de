"""The detection picture: panels with labelled axes in the cloud's units, for a found target,
a missing one and a cloud with no wall."""

from __future__ import annotations

import numpy as np

from armkit.perception import detect_target, random_scene
from armkit.report.perception import detection_figure, save_detection_figure


def labels(fig):
    return [(ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes if ax.axison]


def test_found_pipe_in_millimetres(tmp_path):
    scene = random_scene(0, n_points=20_000)
    result = detect_target(scene.points, radius=0.04)
    object.__setattr__(result, "file_units", "mm")
    fig = detection_figure(result)
    assert labels(fig) == [("along the wall, u (mm)", "along the wall, v (mm)"),
                           ("u (mm)", "v (mm)"), ("u (mm)", "height above the wall (mm)")]
    close_up = fig.axes[1]
    lo, hi = close_up.get_xlim()
    assert abs(hi - lo - 240.0) < 1e-9                     # +-3 radii, in mm
    assert "fitted circle, r = 40 mm (known)" in [t.get_text()
                                                  for t in close_up.get_legend().get_texts()]
    path = save_detection_figure(result, tmp_path, "scan")
    assert path.name == "scan.png" and path.read_bytes()[:4] == b"\x89PNG"


def test_no_target_and_no_wall():
    scene = random_scene(0, "hole", n_points=20_000)
    fig = detection_figure(detect_target(scene.points))            # a pipe asked for: none
    assert fig._suptitle.get_text().startswith("no target:")
    blob = np.random.default_rng(0).normal([1.5, 0, 0], 0.3, (3000, 3))
    fig = detection_figure(detect_target(blob))
    assert fig._suptitle.get_text().startswith("no target: no wall")
    assert labels(fig) == [("sensor y (m)", "sensor z (m)")]
