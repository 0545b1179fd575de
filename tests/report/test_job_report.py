"""The job's report as a library writes it: checked before the job (`check_report`), the
record first, one page that holds its figures, and a record for every way a job can stop."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from armkit.errors import InputError
from armkit.io.tasks import demo_task
from armkit.job import run_job
from armkit.report.job import FILES, check_report, summary, write_report


def test_a_writable_folder_passes_and_keeps_nothing(tmp_path):
    out = check_report(demo_task(), tmp_path / "new" / "report")
    assert out.is_dir() and list(out.iterdir()) == []


@pytest.mark.parametrize("blocked", FILES)
def test_a_directory_where_a_file_goes_is_refused(blocked, tmp_path):
    (tmp_path / blocked).mkdir()
    with pytest.raises(InputError, match=f"--out: expected a folder armkit can write {blocked}"):
        check_report(demo_task(), tmp_path)


def test_a_file_where_the_folder_goes_is_refused(tmp_path):
    (tmp_path / "report").write_text("")
    with pytest.raises(InputError, match="--out: expected a folder armkit can write, found "):
        check_report(demo_task(), tmp_path / "report")


def test_a_folder_that_cannot_be_made_is_refused():
    with pytest.raises(InputError, match="--out: expected a folder armkit can write, found "
                                         "/proc/armkit-report"):
        check_report(demo_task(), "/proc/armkit-report")


def test_a_job_stopped_at_the_target_has_a_record_and_a_page(tmp_path):
    """A job that stopped before anything moved: every key of the record is there (None for
    the steps not reached), JSON without NaN, and the page says why."""
    task = demo_task()
    far = task.target.T_camera_target.copy()
    far[:3, 3] += [5.0, 0, 0]
    result = run_job(replace(task, target=replace(task.target, T_camera_target=far)))
    written = write_report(result, tmp_path)
    assert [p.name for p in written] == ["summary.json", "tool_path.png", "report.html"]
    doc = json.loads((tmp_path / "summary.json").read_text())
    assert doc == summary(result) | {"timings_s": doc["timings_s"]}
    assert doc["stopped_at"] == "ik" and doc["motion"] is None and doc["sent"] is None
    page = (tmp_path / "report.html").read_text()
    assert "Stopped at ik: no IK solution: out of reach" in page


def test_the_record_carries_the_motion_and_its_checks(tmp_path):
    result = run_job(demo_task())
    doc = summary(result)
    assert doc["motion"]["duration_s"] == pytest.approx(result.motion.trajectory.duration,
                                                        abs=1e-4)
    assert set(doc["checks"].values()) == {"ok"}
    jerk = np.array(list(doc["motion"]["peak_jerk"].values()))
    limits = result.task.robot.q_from_si(result.task.robot.jerk_limits)
    assert (jerk <= limits * (1 + 1e-6)).all()
    assert doc["q_reported"] == doc["q_final"]
