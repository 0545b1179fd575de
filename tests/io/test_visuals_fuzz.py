"""Hostile visual elements: a URDF whose <visual> parts are mutated loads as a robot (the
kinematics read none of them) and its visuals read into shapes, notes, or one ModelFileError
naming the file and element; never a traceback."""

from __future__ import annotations

import numpy as np
import pytest

import armkit
from armkit.errors import ModelFileError
from armkit.io.visuals import read_visuals

URDF = """<?xml version="1.0"?>
<robot name="two">
  <link name="base"><visual><origin xyz="0 0 0.05" rpy="0 0 0"/>
    <geometry><box size="0.2 0.2 0.1"/></geometry></visual></link>
  <link name="arm"><visual><origin xyz="0.2 0 0" rpy="0 1.5708 0"/>
    <geometry><cylinder radius="0.03" length="0.4"/></geometry></visual>
    <visual><geometry><sphere radius="0.05"/></geometry></visual></link>
  <link name="hand"><visual><geometry><mesh filename="package://two/hand.stl" scale="1 1 1"/>
    </geometry></visual></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="fixed_hand" type="fixed"><parent link="arm"/><child link="hand"/>
    <origin xyz="0.4 0 0"/></joint>
</robot>
"""
VALUES = ["", "nan", "inf", "1e400", "-0", "1 2", "x", "1,2,3", "0x10", "１", "1e3 0 0",
          "0 0 0 0", "   ", "\u00a0", "1_0", "+1", ".5", "5.", "-1e-400"]


def mutants(count: int, seed: int):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        text = URDF
        for _ in range(int(rng.integers(1, 4))):
            attribute = rng.choice(['xyz="', 'rpy="', 'size="', 'radius="', 'length="',
                                    'scale="', 'filename="'])
            at = [i for i in range(len(text)) if text.startswith(attribute, i)]
            if not at:
                continue
            i = int(rng.choice(at)) + len(attribute)
            end = text.index('"', i)
            text = text[:i] + str(rng.choice(VALUES)) + text[end:]
        if rng.random() < 0.2:               # an element cut out or broken
            cut = int(rng.integers(0, len(text)))
            text = text[:cut] + text[cut + int(rng.integers(1, 40)):]
        yield text


def _read(path) -> str:
    try:
        robot = armkit.load_robot(path)
    except ModelFileError:
        return "refused as a robot"
    try:
        found = read_visuals(robot)
    except ModelFileError as err:
        assert str(path) in str(err) and "\n" not in str(err)
        return "visual refused"
    if found is None:
        return "no visuals"
    for shape in found.shapes:
        assert np.isfinite(shape.T).all() and np.isfinite(shape.size).all()
    return "read"


def _run(tmp_path, count, seed):
    outcomes: dict[str, int] = {}
    for k, text in enumerate(mutants(count, seed)):
        path = tmp_path / f"m{k}.urdf"
        path.write_text(text)
        outcome = _read(path)
        outcomes[outcome] = outcomes.get(outcome, 0) + 1
    assert outcomes.get("read", 0) > 0 and outcomes.get("visual refused", 0) > 0, outcomes


def test_the_clean_file_reads_its_three_primitives_and_notes_the_missing_mesh(tmp_path):
    path = tmp_path / "two.urdf"
    path.write_text(URDF)
    found = read_visuals(armkit.load_robot(path))
    assert [s.kind for s in found.shapes] == ["box", "cylinder", "sphere"]
    assert [s.link for s in found.shapes] == [0, 1, 1]
    assert found.notes == ("link 'hand' <visual>[0]: mesh 'package://two/hand.stl' not found",)


def test_mutated_visuals(tmp_path):
    _run(tmp_path, 150, seed=5)


@pytest.mark.slow
def test_many_mutated_visuals(tmp_path):
    _run(tmp_path, 2000, seed=6)
