"""`armkit ik --all` on an arm without a closed form: the numeric solution, and a word that
there is no closed form (run as users run it: the real command in a subprocess)."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import armkit

pytestmark = pytest.mark.slow      # commands run as users run them: CI runs them all


def armkit_ik(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "armkit", "ik", *args], capture_output=True,
                          text=True, timeout=300)


def test_all_on_the_panda_prints_the_numeric_solution_and_says_there_is_no_closed_form():
    panda = armkit.robot("panda")
    T = armkit.fk(panda, [0.2, -0.4, 0.1, -2.0, 0.3, 1.6, 0.5])
    pose = [f"{v:.12g}" for v in T[:3, 3]]
    text = armkit_ik("panda", "--pose", *pose, "--all")
    assert text.returncode == 0 and text.stderr == "", text.stderr
    assert "closed form: none for panda" in text.stdout and "solved" in text.stdout
    doc = json.loads(armkit_ik("panda", "--pose", *pose, "--all", "--json").stdout)
    assert doc["success"] is True and doc["closed_form"] is None and "solutions" not in doc
    reached = armkit.fk(panda, panda.q_to_si(doc["q"]))
    np.testing.assert_allclose(reached[:3, 3], T[:3, 3], atol=1e-9)


def test_position_and_yaw_on_the_ur5_is_solved():
    """The issue's case: `--yaw` on a 6-joint arm printed "did not converge" and exited 1."""
    text = armkit_ik("ur5", "--pose", "0.4", "0.1", "0.3", "--yaw", "0", "--json")
    assert text.returncode == 0, text.stdout
    doc = json.loads(text.stdout)
    assert doc["success"] is True and doc["mask"] == "position+yaw"
