"""`armkit workspace`: numbers in the file's units, figures written, Dask, bad input."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import armkit
import armkit.cli.workspace as command
from armkit.cli import app

pytestmark = pytest.mark.slow      # commands run as users run them: CI runs them all

runner = CliRunner()


def run(*args: str):
    return runner.invoke(app, list(args))


def test_json_in_millimetres_and_two_figures(tmp_path):
    result = run("workspace", "water_supply", "-n", "2e4", "--seed", "4", "--resolution", "100",
                 "--out", str(tmp_path / "figs"), "--json")
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    ws = armkit.workspace(armkit.robot("water_supply"), 20_000, seed=4, resolution=0.1)
    assert doc["units"] == {"length": "mm", "angle": "deg"} and doc["samples"] == 20_000
    assert doc["resolution"] == pytest.approx(100)
    assert doc["bounds"]["lower"] == pytest.approx(ws.lower * 1000)
    assert doc["bounds"]["upper"] == pytest.approx(ws.upper * 1000)
    assert 525.5 <= doc["bounds"]["lower"][2] and doc["bounds"]["upper"][2] <= 1125.5
    assert doc["reach"] == pytest.approx(ws.reach * 1000)
    assert doc["volume"] == pytest.approx(ws.volume * 1e9)
    assert doc["volume_history"][-1] == [20_000, pytest.approx(ws.volume * 1e9)]
    horizontal, vertical = doc["sections"]
    assert horizontal["height"] == pytest.approx(850)        # middle of the layer 800 .. 900
    assert horizontal["area"] == pytest.approx(ws.horizontal_section(0.85).area * 1e6)
    assert vertical["azimuth"] == 0 and vertical["area"] > 0
    for path in doc["figures"]:
        with open(path, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in (tmp_path / "figs").iterdir()) == [
        "water_supply_sections.png", "water_supply_workspace.png"]


def test_text_and_si(tmp_path):
    result = run("workspace", "tool_changer_6dof", "-n", "20000", "--out", str(tmp_path),
                 "--height", "500", "--azimuth", "90")
    assert result.exit_code == 0, result.output
    text = result.stdout
    assert "20,000 samples, seed 0, voxels of 100 mm" in text
    assert "bounds (mm):  x " in text and "from the base origin" in text
    assert "volume (mm³):" in text and "sections (mm²):  z = 500:" in text
    assert "azimuth 90 deg" in text and "tool_changer_6dof_sections.png" in text
    doc = json.loads(run("workspace", "tool_changer_6dof", "-n", "20000", "--out",
                         str(tmp_path), "--json", "--si").stdout)
    assert doc["units"]["length"] == "m" and doc["resolution"] == pytest.approx(0.1)
    assert doc["bounds"]["upper"][0] <= 2.8


def test_long_runs_show_progress_on_stderr_only(tmp_path, monkeypatch):
    monkeypatch.setattr(command, "PROGRESS_FROM", 1)
    result = run("workspace", "ur5", "-n", "3000", "--out", str(tmp_path), "--json")
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["samples"] == 3000


@pytest.mark.parametrize("args, words", [
    (("-n", "0"), "armkit: -n: expected a whole number from 1 to 1e+10 samples in this "
                  "process (--scheduler for more), found 0"),
    (("-n", "lots"), "armkit: -n: expected a whole number from 1 to 1e+10"),
    (("-n", "2.5"), "armkit: -n: expected a whole number"),
    (("-n", "1e20"), "armkit: -n: expected a whole number from 1 to 1e+10 samples in this "
                     "process (--scheduler for more), found 1e+20"),
    (("--resolution", "-5"), "armkit: --resolution: expected a number above 0 and at most "
                             "1e+09, found -5"),
    (("--resolution", "1e308"), "armkit: --resolution: expected a number above 0"),
    (("--height", "1e308"), "armkit: --height: expected a number from -1e+09 to 1e+09"),
    (("--resolution", "0.001"), "armkit: resolution: expected at least 0.000202 m"),
    (("--scheduler", "nowhere"), "armkit: scheduler: expected an address such as "
                                 "tcp://127.0.0.1:8786, found 'nowhere'"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, args, words):
    result = run("workspace", "inspection_6dof", "--out", str(tmp_path), *args)
    assert result.exit_code == 2, result.output
    assert result.stderr.strip().splitlines() == [result.stderr.strip()]
    assert words in result.stderr and result.stdout == ""
    assert list(tmp_path.iterdir()) == []


def test_the_real_command(tmp_path):
    env = {**os.environ, "COLUMNS": "120"}
    done = subprocess.run([sys.executable, "-m", "armkit", "workspace", "modular_4dof", "-n",
                           "5000", "--out", str(tmp_path), "--json"], capture_output=True,
                          text=True, env=env, timeout=120)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["robot"] == "modular_4dof"


@pytest.fixture(scope="module")
def scheduler_address(tmp_path_factory):
    """A Dask scheduler and one worker started as a user starts them: `dask scheduler` and
    `dask worker`, separate processes on loopback, an ephemeral port."""
    folder = tmp_path_factory.mktemp("dask")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(Path(armkit.__file__).parents[1]), os.environ.get("PYTHONPATH", "")])}
    dask = [sys.executable, "-m", "dask"]
    scheduler_file = folder / "scheduler.json"
    processes = [subprocess.Popen(
        [*dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
         "--scheduler-file", str(scheduler_file)], cwd=folder, env=env,
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        deadline = time.monotonic() + 120
        while not scheduler_file.exists():
            assert time.monotonic() < deadline and processes[0].poll() is None
            time.sleep(0.2)
        processes.append(subprocess.Popen(
            [*dask, "worker", "--scheduler-file", str(scheduler_file), "--nthreads", "1",
             "--nworkers", "1", "--no-dashboard"], cwd=folder, env=env,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        address = json.loads(scheduler_file.read_text())["address"]
        from distributed import Client

        with Client(address, timeout="60s", set_as_default=False) as client:
            client.wait_for_workers(1, timeout=120)
        yield address
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in processes:
            try:
                process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                process.kill()


def test_workspace_on_a_scheduler_by_address_from_the_command_line(tmp_path, scheduler_address):
    args = [sys.executable, "-m", "armkit", "workspace", "inspection_6dof", "-n", "30000",
            "--out", str(tmp_path), "--json"]
    done = subprocess.run([*args, "--scheduler", scheduler_address], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    local = json.loads(run(*args[3:]).stdout)
    remote = json.loads(done.stdout)
    assert {k: v for k, v in remote.items() if k != "figures"} == {
        k: v for k, v in local.items() if k != "figures"}


def test_workspace_on_a_scheduler_by_address_from_python(scheduler_address):
    robot = armkit.robot("modular_4dof")
    remote = armkit.workspace(robot, 50_000, seed=3, scheduler=scheduler_address)
    local = armkit.workspace(robot, 50_000, seed=3)
    np.testing.assert_array_equal(remote.voxels, local.voxels)
    assert remote.volume == local.volume and remote.reach == local.reach


def test_a_bad_scheduler_address_is_one_line_and_nothing_after(tmp_path):
    # These two once printed their line, then, as the process ended, a Client's 20 s close and
    # an "Exception ignored ... TimeoutError" traceback. The other bad addresses are in
    # test_bad_input_table.
    rows = {"127.0.0.1": "expected an address such as tcp://127.0.0.1:8786, found '127.0.0.1'",
            "bogus://127.0.0.1:5": "(schemes: inproc, tcp"}
    processes = {address: subprocess.Popen(
        [sys.executable, "-m", "armkit", "workspace", "ur5", "-n", "1000", "--out",
         str(tmp_path), "--scheduler", address], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True) for address in rows}
    for address, process in processes.items():
        _, stderr = process.communicate(timeout=300)
        assert process.returncode == 2
        assert stderr.strip().splitlines() == [stderr.strip()], stderr
        assert rows[address] in stderr and "Traceback" not in stderr


def test_without_a_terminal_a_long_run_says_how_long_before_it_goes_on(tmp_path, monkeypatch):
    monkeypatch.setattr(command, "PROGRESS_FROM", 1)
    monkeypatch.setattr(command, "ESTIMATE_FROM", 0.0)
    result = run("workspace", "ur5", "-n", "300000", "--out", str(tmp_path), "--json")
    assert result.exit_code == 0, result.stderr
    lines = result.stderr.splitlines()
    assert lines[0].startswith("sampling 300,000 joint vectors: about ") and " left" in lines[0]
    assert any(line.startswith("sampled ") for line in lines[1:])
    assert json.loads(result.stdout)["samples"] == 300_000
