"""Register maps: encoding against hand-derived words and pymodbus's own conversion, and one
precise message per mistake in a map file (file, field, expected, found)."""

from __future__ import annotations

import textwrap

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from pymodbus.client import ModbusTcpClient

import armkit
from armkit.drives import JointRegister
from armkit.drives.registers import MAX_WRITE, default_register_map, runs
from armkit.errors import ModelFileError
from armkit.io.register_maps import builtin_register_map, load_register_map
from tests.drives.conftest import INSPECTION, ROOT, WATER, waypoints


@pytest.mark.parametrize("kind, value, word, byte, expected", [
    ("int32", 10, "big", "big", [0x0000, 0x2710]),            # 10 deg x 1000 = 0x2710
    ("int32", 10, "little", "big", [0x2710, 0x0000]),
    ("int32", 10, "big", "little", [0x0000, 0x1027]),
    ("int32", 10, "little", "little", [0x1027, 0x0000]),
    ("int32", -0.001, "big", "big", [0xFFFF, 0xFFFF]),
    ("float32", 0.001, "big", "big", [0x3F80, 0x0000]),       # 1.0f = 0x3F800000
    ("float32", 0.001, "little", "big", [0x0000, 0x3F80]),
    ("float32", 0.001, "big", "little", [0x803F, 0x0000]),
    ("int16", -0.002, "big", "big", [0xFFFE]),
    ("int16", -0.002, "little", "little", [0xFEFF]),
    ("uint16", 0.513, "big", "big", [0x0201]),
    ("uint16", 0.513, "big", "little", [0x0102]),
])
def test_words_by_hand(kind, value, word, byte, expected):
    joint = JointRegister("j", 0, kind, 1000.0, word, byte)
    assert joint.words(value).tolist() == expected
    assert joint.words([value, value]).tolist() == [expected, expected]
    assert joint.value(expected) == pytest.approx(value, abs=1e-12)


@pytest.mark.parametrize("kind", ["int16", "uint16", "int32", "float32"])
@pytest.mark.parametrize("word", ["big", "little"])
def test_words_match_pymodbus(kind, word):
    """pymodbus's convert_to_registers is an independent reference (high byte first)."""
    values = {"int16": [-32768, -1, 0, 12345, 32767], "uint16": [0, 1, 65535, 4660],
              "int32": [-2**31, -1, 0, 123456789, 2**31 - 1],
              "float32": [0.0, -1.5, 3.1415927, 1e-20, 3.0e38]}[kind]
    data_type = getattr(ModbusTcpClient.DATATYPE, kind.upper())
    joint = JointRegister("j", 0, kind, 1.0, word, "big")
    for v in values:
        assert joint.words(v).tolist() == ModbusTcpClient.convert_to_registers(
            v, data_type, word_order=word), v


@given(st.sampled_from(["int16", "uint16", "int32", "float32"]),
       st.sampled_from(["big", "little"]), st.sampled_from(["big", "little"]),
       st.lists(st.floats(0, 1), min_size=1, max_size=5))
def test_round_trip_within_half_a_count(kind, word, byte, fractions):
    joint = JointRegister("j", 0, kind, 7.5, word, byte)
    lo, hi = joint.counts_range
    lo, hi = max(lo, -1e6), min(hi, 1e6)
    value = (lo + (hi - lo) * np.array(fractions)) / joint.scale
    back = joint.value(joint.words(value))
    if kind == "float32":
        sent = (value * joint.scale).astype(np.float32)
        np.testing.assert_array_equal(back, sent.astype(float) / joint.scale)
    else:
        assert np.all(np.abs(back - value) * joint.scale <= 0.5 + 1e-9)   # a tie may round away


def test_map_encodes_batches_like_single_waypoints(any_map):
    q = waypoints(any_map, 6).reshape(2, 3, -1)
    blocks = any_map.encode(q)
    assert blocks.shape == (2, 3, any_map.block_count) and blocks.dtype == np.uint16
    assert blocks[1, 2].tolist() == any_map.encode(q[1, 2]).tolist()
    np.testing.assert_allclose(any_map.decode(blocks), q, atol=1e-3)


def test_example_maps_load():
    m = load_register_map(INSPECTION)
    assert (m.robot.name, m.device_id, m.block_start, m.block_count) == ("inspection_6dof",
                                                                         1, 0, 13)
    assert m.ack_reads == ((0, 16),) and m.enable == 28
    w = load_register_map(WATER)
    assert (w.robot.name, w.n, w.device_id, w.block_start, w.block_count) == (
        "water_supply", 4, 3, 100, 6)
    assert [j.type for j in w.joints] == ["float32", "int16", "int16", "int16"]
    assert w.joints[0].word_order == "little"


@pytest.mark.parametrize("example", [INSPECTION, WATER])
def test_packaged_maps_are_the_examples(example):
    packaged = ROOT / "src" / "armkit" / "drives" / example.name
    assert packaged.read_text() == example.read_text()


def test_robot_argument_overrides_the_file(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text(INSPECTION.read_text().replace("robot: inspection_6dof\n", ""))
    with pytest.raises(ModelFileError, match="robot: expected the robot the map drives"):
        load_register_map(path)
    assert load_register_map(path, armkit.robot("inspection_6dof")).robot.n == 6


def test_robot_file_relative_to_the_map(tmp_path):
    armkit.save_robot(armkit.robot("inspection_6dof"), tmp_path / "arm.yaml")
    path = tmp_path / "m.yaml"
    path.write_text(INSPECTION.read_text().replace("robot: inspection_6dof", "robot: arm.yaml"))
    assert load_register_map(path).robot.name == "inspection_6dof"


def test_runs():
    assert runs({5, 1, 2, 3, 7}, 125) == ((1, 3), (5, 1), (7, 1))
    assert runs(range(130), 125) == ((0, 125), (125, 5))


GOOD = INSPECTION.read_text()


@pytest.mark.parametrize("old, new, field, words", [
    ("target: 0,", "target: 70000,", "joints[0].target", "less than or equal to 65535, "
     "found 70000"),
    ("target: 2,", "target: 1,", "joints[1].target", "a register of its own, found 1..2, "
     "which joints[0].target also uses (0..1)"),
    ("state: 14", "state: 12", "status.state", "a register of its own, found 12, which "
     "command.waypoint also uses (12)"),
    ("actual: 26,", "actual: 27,", "command.enable", "found 28, which joints[5].actual also uses "
     "(27..28)"),
    ("waypoint: 12", "waypoint: 200", "joints", f"at most {MAX_WRITE} registers, one FC16 "
     "write, found 201 registers (0..200)"),
    ("waypoint: 12", "waypoint: 29", "command.waypoint", "one contiguous run of registers "
     "(one write covers them all), found a gap at 12..28"),
    ("target: 10, actual: 26", "target: 65535, actual: 26", "joints[5].target",
     "registers within 0..65535, found 65535..65536"),
    ("target: 0, actual: 16, type: int32", "target: 0, actual: 16, type: int16",
     "joints[0].type", "a type that holds the joint's limits -180..180 deg at scale 1000 "
     "(-180000..180000 counts), found int16 (-32768..32767)"),
    ("target: 0, actual: 16, type: int32, scale: 1000", "target: 0, actual: 16, type: uint16, "
     "scale: 100", "joints[0].type", "found uint16 (0..65535)"),
    ("type: int32, scale: 1000}\n  - {name: q2", "type: int32, scal: 1000}\n  - {name: q2",
     "joints[0]", "(did you mean 'scale'?), found unknown field 'scal'"),
    ("accepted: 13", "acepted: 13", "status", "(did you mean 'accepted'?)"),
    ("type: int32, scale: 1000}\n  - {name: q2", "type: int64, scale: 1000}\n  - {name: q2",
     "joints[0].type", "'int16', 'uint16', 'int32' or 'float32', found 'int64'"),
    ("word_order: big", "word_order: middle", "word_order", "'big' or 'little'"),
    ("scale: 1000}\n  - {name: q2", "scale: 0}\n  - {name: q2", "joints[0].scale",
     "greater than 0, found 0"),
    ("  - {name: q6, target: 10, actual: 26, type: int32, scale: 1000}\n", "", "joints",
     "6 entries (the joints of inspection_6dof), found 5"),
    ("name: q2", "name: elbow", "joints[1].name", "'q2' (joint 2 of inspection_6dof), found "
     "'elbow'"),
    ("robot: inspection_6dof", "robot: inspection_7dof", "robot", "a built-in robot name or a "
     "robot file, found 'inspection_7dof'"),
    ("  accepted: 13 ", "  # ", "status.accepted", "a register, since command.waypoint is "
     "given"),
    ("readback: true", "readbak: true", "top level", "(did you mean 'readback'?)"),
    ("device_id: 1", "device_id: 300", "device_id", "less than or equal to 255"),
    ("target: 4,", "target: four,", "joints[2].target", "a valid integer, found 'four'"),
    ("target: 4,", "target: 4.5,", "joints[2].target", "a valid integer, found 4.5"),
    ("{name: q4, target: 6, ", "{name: q4, ", "joints[3].target", "a value, found nothing"),
    ("actual: 22, ", "", "joints[3].actual", "an actual-position register, as the other "
     "joints have, found none"),
    ("scale: 1000}\n  - {name: q2", "scale: true}\n  - {name: q2", "joints[0].scale",
     "a valid number, found True"),
    ("enable: 28", "enable: 28\n  lock: 13", "status.accepted",
     "a register of its own, found 13, which command.lock also uses (13)"),
    ("enable: 28", "enable: 28\n  reset: 70000", "command.reset",
     "less than or equal to 65535"),
    ("enable: 28", "enable: 28\n  lock: true", "command.lock", "a valid integer, found True"),
    ("readback: true", "readback: true\nout_of_limits: {response: stop}",
     "out_of_limits.response", "'exception' or 'fault', found 'stop'"),
    ("readback: true", "readback: true\nout_of_limits: {response: fault, fault_code: 0}",
     "out_of_limits.fault_code", "greater than or equal to 1, found 0"),
    ("readback: true", "readback: 1", "readback", "a valid boolean, found 1"),
])
def test_each_mistake_names_its_field(tmp_path, old, new, field, words):
    assert old in GOOD, old
    path = tmp_path / "bad.map.yaml"
    path.write_text(GOOD.replace(old, new, 1))
    with pytest.raises(ModelFileError) as err:
        load_register_map(path)
    message = str(err.value)
    assert message.startswith(f"{path}: "), message
    assert f": {field}: expected" in message or not field, message
    assert words in message, message


def test_readback_off_needs_an_index(tmp_path):
    text = textwrap.dedent("""\
        robot: water_supply
        readback: false
        joints:
          - {target: 0, type: float32}
          - {target: 2, type: float32}
          - {target: 4, type: float32}
          - {target: 6, type: float32}
        """)
    path = tmp_path / "m.yaml"
    path.write_text(text)
    with pytest.raises(ModelFileError, match=r"m.yaml: readback: expected true, or "
                                             r"command.waypoint and status.accepted"):
        load_register_map(path)
    path.write_text(text.replace("readback: false", "readback: true"))
    assert load_register_map(path).ack_reads == ((0, 8),)


def test_not_a_mapping_and_bad_yaml(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text("- 1\n")
    with pytest.raises(ModelFileError, match="expected a mapping of fields"):
        load_register_map(path)
    path.write_text("robot: [\n")
    with pytest.raises(ModelFileError, match="m.yaml: line 2: expected valid YAML"):
        load_register_map(path)


def test_a_fault_response_needs_a_register_to_report_it(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text(textwrap.dedent("""\
        robot: water_supply
        out_of_limits: {response: fault}
        joints:
          - {target: 0, type: float32}
          - {target: 2, type: float32}
          - {target: 4, type: float32}
          - {target: 6, type: float32}
        """))
    with pytest.raises(ModelFileError, match=r"m.yaml: out_of_limits.response: expected "
                                             r"exception, since the map has no status.state"):
        load_register_map(path)


def test_lock_reset_and_limit_response_load(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text(GOOD.replace("enable: 28", "enable: 28\n  lock: 29\n  reset: 30")
                    + "out_of_limits: {response: fault, fault_code: 0x5530}\n")
    m = load_register_map(path)
    assert (m.lock, m.reset, m.limit_response, m.limit_fault_code) == (29, 30, "fault", 0x5530)
    assert m.ack_reads == ((0, 16), (29, 1))                    # the lock is read with the status


@pytest.mark.parametrize("text, field, words", [
    ("a: &a [x, x, x, x, x, x, x, x]\nb: &b [*a, *a, *a, *a, *a, *a, *a, *a]\n"
     "c: &c [*b, *b, *b, *b, *b, *b, *b, *b]\nd: &d [*c, *c, *c, *c, *c, *c, *c, *c]\n"
     "e: &e [*d, *d, *d, *d, *d, *d, *d, *d]\nf: [*e, *e, *e, *e, *e, *e, *e, *e]\n",
     "line 2", "anchors and aliases are not supported"),     # refused before any is built
    ("robot: x\njoints: " + "[" * 12 + "]" * 12 + "\n", "line 2", "fields nested at most 8"),
    ("robot: " + "[" * 3000 + "]" * 3000 + "\n", "line 1", "fields nested at most 8 deep"),
    ("robot:\n" + "".join(" " * (2 * i + 2) + "-\n" for i in range(20)) + " " * 42 + "x\n",
     "robot", "fields nested at most 8 deep"),                  # block style, no brackets
])
def test_alias_bombs_and_deep_nesting_are_refused(tmp_path, text, field, words):
    path = tmp_path / "m.yaml"
    path.write_text(text)
    with pytest.raises(ModelFileError) as err:
        load_register_map(path)
    assert str(err.value).startswith(f"{path}: ") and words in str(err.value), str(err.value)
    assert err.value.field.startswith(field)


@pytest.mark.parametrize("name", ["water_supply", "inspection_6dof", "panda", "ur5"])
def test_half_a_count_is_what_a_register_round_trip_can_move(name):
    """`RegisterMap.half_count` bounds how far a value moves when the drive stores it: for
    any q within the limits, encoding and decoding moves each joint by at most that."""
    robot = armkit.robot(name)
    m = builtin_register_map(robot)
    q = np.random.default_rng(3).uniform(robot.lower, robot.upper, (200, robot.n))
    moved = np.abs(m.decode(m.encode(q)) - q)
    bound = np.array([m.half_count(qi) for qi in q])
    assert (moved <= bound * (1 + 1e-9) + 1e-15).all()
    # ... and is reached (to within a tenth) by some value: it is not a loose bound.
    assert (moved.max(axis=0) >= 0.1 * bound.max(axis=0)).all()


def test_the_default_map_drives_any_robot_on_the_simulated_drive():
    robot = armkit.robot("panda")
    m = default_register_map(robot)
    assert m.n == robot.n and m.moving_bit == 1 and m.block_count == 2 * robot.n + 1
    q = waypoints(m, 3)
    with armkit.SimDrive(m) as sim, armkit.DriveClient(m, port=sim.port, timeout=0.5) as drive:
        assert drive.send(q).last_accepted == 2
        status = drive.status()
    assert status.moving in (True, False) and not status.faulted


def test_a_moving_bit_is_a_state_bit_other_than_the_fault_bit(tmp_path):
    assert "moving_bit: 1" in GOOD
    for new, found in (("moving_bit: 15", "15, the fault bit"), ("moving_bit: 16", "16")):
        path = tmp_path / "bad.map.yaml"
        path.write_text(GOOD.replace("moving_bit: 1", new, 1))
        with pytest.raises(ModelFileError, match=f"status.moving_bit: expected .*found {found}"):
            load_register_map(path)
    assert load_register_map(WATER).moving_bit == 1
