"""`armkit send` and `armkit sim-drive`: in-process against a simulated drive on loopback, and
once end to end with both as real processes."""

from __future__ import annotations

import json
import os
import re
import select
import subprocess
import sys

import numpy as np
import pytest
from typer.testing import CliRunner

from armkit.cli import app
from armkit.drives import SimDrive
from armkit.io.register_maps import load_register_map
from tests.drives.conftest import INSPECTION, WATER

runner = CliRunner()
MAP = str(INSPECTION)
CSV = "t,q1,q2,q3,q4,q5,q6\n0,0,0,0,0,0,0\n1,10,20,30,40,50,60\n2,20,30,40,50,60,70\n"


def run(*args: str):
    return runner.invoke(app, list(args))


@pytest.fixture
def csv_file(tmp_path):
    path = tmp_path / "wp.csv"
    path.write_text(CSV)
    return path


@pytest.fixture
def sim():
    with SimDrive(load_register_map(INSPECTION)) as drive:
        yield drive


def test_dry_run_checks_and_encodes_without_connecting(csv_file):
    result = run("send", str(csv_file), "--map", MAP, "--dry-run", "--json", "--port", "1")
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert doc["ok"] and doc["dry_run"] and doc["waypoints"] == 3 and doc["velocity_checked"]
    assert doc["write"] == {"device_id": 1, "address": 0, "count": 13,
                            "acknowledge_reads": [[0, 16]]}
    assert doc["registers"][1] == [0, 10000, 0, 20000, 0, 30000, 0, 40000, 0, 50000, 0, 60000,
                                   0]
    text = run("send", str(csv_file), "--map", MAP, "--dry-run").stdout
    assert "3 waypoints within the joint limits" in text and "nothing sent" in text


def test_send_to_the_simulated_drive(csv_file, sim):
    result = run("send", str(csv_file), "--map", MAP, "--port", str(sim.port), "--json")
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert doc["ok"] and doc["last_accepted"] == 2 and doc["waypoints"] == 3
    np.testing.assert_allclose(np.rad2deg(sim.targets()), [20, 30, 40, 50, 60, 70], atol=1e-9)
    text = run("send", str(csv_file), "--map", MAP, "--port", str(sim.port)).stdout
    assert re.match(r"sent 3 waypoints to 127.0.0.1:\d+ in [\d.]+ ms; the drive took "
                    r"waypoints 0..2", text), text


def test_json_waypoints_and_no_header(tmp_path, sim):
    path = tmp_path / "wp.json"
    path.write_text(json.dumps({"q": [[0] * 6, [1, 2, 3, 4, 5, 6]], "t": [0, 1]}))
    assert run("send", str(path), "--map", MAP, "--port", str(sim.port)).exit_code == 0
    path.write_text(json.dumps([[0, 0, 0, 0, 0, 0, 0], [1, 1, 2, 3, 4, 5, 6]]))
    doc = json.loads(run("send", str(path), "--map", MAP, "--dry-run", "--json").stdout)
    assert doc["velocity_checked"] and doc["waypoints"] == 2
    path = tmp_path / "wp.csv"
    path.write_text("1,2,3,4,5,6\n")
    doc = json.loads(run("send", str(path), "--map", MAP, "--dry-run", "--json").stdout)
    assert not doc["velocity_checked"] and doc["registers"][0][:2] == [0, 1000]


def test_a_failed_send_prints_the_report_and_exits_1(csv_file, sim):
    sim.inject("exception", at=1)
    result = run("send", str(csv_file), "--map", MAP, "--port", str(sim.port), "--json")
    assert result.exit_code == 1
    doc = json.loads(result.stdout)
    assert doc == {**doc, "ok": False, "failed_waypoint": 1, "last_accepted": 0,
                   "outcome_unknown": False, "cause": "Modbus exception 4 (device failure)"}
    sim.clear()
    sim.inject("drop", at=sim.waypoint_writes + 2)
    result = run("send", str(csv_file), "--map", MAP, "--port", str(sim.port))
    assert result.exit_code == 1
    assert result.stdout.splitlines() == [
        "send failed at waypoint 2 of 3 (counted from 0): connection lost",
        "last accepted waypoint: 1",
        "whether the drive took waypoint 2: unknown (its write left, no answer came back)"]


def test_no_drive_listening_is_a_failed_send(csv_file):
    result = run("send", str(csv_file), "--map", MAP, "--port", "1", "--timeout", "0.3")
    assert result.exit_code == 1
    assert "send failed at waypoint 0 of 3" in result.stdout
    assert "last accepted waypoint: none" in result.stdout and result.stderr == ""


@pytest.mark.parametrize("content, map_path, words", [
    (CSV.replace("1,10,20", "1,190,20"), MAP,
     "armkit: waypoint 1, joint q1: 190 deg outside the limits -180..180 deg"),
    (CSV.replace("2,20,30", "1.5,120,30"), MAP,
     "armkit: waypoints 1 -> 2, joint q1: 220 deg/s over the velocity limit 90 deg/s"),
    (CSV.replace("q6", "q7"), MAP, "line 1: expected a header naming each joint"),
    (CSV.replace("1,10,20,30", "1,10,x,30"), MAP, "wp.csv: line 3: expected 7 numbers"),
    ("1,2,3\n", MAP, "line 1: expected 6 numbers (the joints of inspection_6dof), or 7"),
    (CSV, str(WATER), "expected a header naming each joint of water_supply"),
    (CSV, "missing.map.yaml", "missing.map.yaml: expected a readable file"),
    (CSV.replace("1,10,20,30", "1,10,nan,30"), MAP,
     "wp.csv: line 3, column 3: expected a valid number from -1e+09 to 1e+09, found 'nan'"),
    (CSV.replace("2,20,30", "2,inf,30"), MAP, "wp.csv: line 4, column 2: expected a valid "
                                              "number"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, content, map_path, words):
    path = tmp_path / "wp.csv"
    path.write_text(content)
    result = run("send", str(path), "--map", map_path, "--port", "1")
    assert result.exit_code == 2, result.output
    assert result.stderr.strip().splitlines() == [result.stderr.strip()]
    assert words in result.stderr and result.stdout == ""


def test_a_bad_map_names_its_field(tmp_path, csv_file):
    path = tmp_path / "bad.map.yaml"
    path.write_text(INSPECTION.read_text().replace("target: 2,", "target: 1,"))
    result = run("send", str(csv_file), "--map", str(path), "--dry-run")
    assert result.exit_code == 2
    assert f"{path}: joints[1].target: expected a register of its own" in result.stderr


def test_sim_drive_and_send_as_real_processes(csv_file):
    env = {**os.environ, "COLUMNS": "200"}
    server = subprocess.Popen([sys.executable, "-m", "armkit", "sim-drive", "--port", "0"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        ready, _, _ = select.select([server.stdout], [], [], 60)    # bounded: never hangs
        line = server.stdout.readline() if ready else ""            # printed once it listens
        port = re.search(r"listening on 127\.0\.0\.1:(\d+)", line)
        assert port, f"sim-drive did not start: {line!r}"
        done = subprocess.run([sys.executable, "-m", "armkit", "send", str(csv_file), "--map",
                               MAP, "--port", port.group(1), "--json"],
                              capture_output=True, text=True, env=env, timeout=60)
        assert done.returncode == 0, done.stderr
        assert json.loads(done.stdout)["last_accepted"] == 2
    finally:
        server.terminate()
        server.wait(timeout=10)


@pytest.mark.parametrize("args, words", [
    (("--timeout", "0"), "armkit: --timeout: expected a number from 0.001 to 3600 s, found 0"),
    (("--timeout", "1e308"), "armkit: --timeout: expected a number from 0.001 to 3600 s, "
                             "found 1e+308"),
    (("--port", "70000"), "armkit: --port: expected a whole number from 1 to 65535, found "
                          "70000"),
    (("--retries", "-1"), "armkit: --retries: expected a whole number from 0 to 100, found -1"),
])
def test_send_options_are_checked_and_named(csv_file, args, words):
    result = run("send", str(csv_file), "--map", MAP, *args)
    assert result.exit_code == 2
    assert result.stderr.strip() == words


def test_nan_in_a_json_waypoint_file_names_the_field(tmp_path):
    path = tmp_path / "wp.json"
    path.write_text('{"q": [[0, 0, 0, 0, 0, 0], [1, 2, NaN, 4, 5, 6]]}')
    result = run("send", str(path), "--map", MAP, "--dry-run")
    assert result.exit_code == 2
    assert f"{path}: q[1][2]: expected a finite number from -1e+09 to 1e+09, found nan" \
        in result.stderr


def test_send_and_sim_drive_share_one_default_port():
    from typer.main import get_command

    group = get_command(app)
    defaults = {name: next(p.default for p in group.commands[name].params if p.name == "port")
                for name in ("send", "sim-drive")}
    assert defaults == {"send": 5020, "sim-drive": 5020}


def test_sim_drive_on_a_busy_port_is_one_line():
    import socket

    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        done = subprocess.run([sys.executable, "-m", "armkit", "sim-drive", "--port", str(port)],
                              capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.strip() == (f"armkit: --port: expected a port free to listen on at "
                                   f"127.0.0.1, found {port} in use (or 127.0.0.1 is not an "
                                   f"address of this machine)")
