"""`armkit run`, `armkit demo` and `armkit view` as users run them: real processes, the
simulated drive on an ephemeral port, the report opened in a real headless browser."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).parents[2] / "examples" / "tasks"
TASKS = sorted(EXAMPLES.glob("*.task.yaml"))


def armkit(*args: str, cwd: Path | None = None, timeout: float = 300):
    return subprocess.run([sys.executable, "-m", "armkit", *args], capture_output=True,
                          text=True, timeout=timeout, cwd=cwd)


def test_every_example_task_runs_while_the_others_do(tmp_path):
    """Each example task as its own `armkit run`, all at once: each job's simulated drive
    takes a loopback port of its own, and the motions (sent in real time) overlap."""
    names = [task.name.split(".")[0] for task in TASKS]
    jobs = {name: subprocess.Popen(
        [sys.executable, "-m", "armkit", "run", str(task), "--out", str(tmp_path / name),
         "--json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        for name, task in zip(names, TASKS)}
    assert len(jobs) == 5
    for name, job in jobs.items():
        out, err = job.communicate(timeout=300)
        assert job.returncode == 0, f"{name}: {err}"
        doc = json.loads(out)
        assert doc["success"] and doc["reason"] == "ok", name
        assert doc["sent"]["last_accepted"] == len(doc["waypoints"]["q"]) - 1, name
        assert doc["position_error"]["m"] <= doc["position_error"]["drive_resolution_m"], name
        assert json.loads((tmp_path / name / "summary.json").read_text())["success"], name


class _References(HTMLParser):
    def __init__(self):
        super().__init__()
        self.found: list[str] = []

    def handle_starttag(self, tag, attrs):
        for key, value in attrs:
            if key in ("src", "href") and value:
                self.found.append(value)


@pytest.fixture(scope="module")
def demo_report(tmp_path_factory) -> Path:
    """`armkit demo` as the README runs it: no arguments, the report in ./armkit-demo."""
    cwd = tmp_path_factory.mktemp("demo")
    done = armkit("demo", cwd=cwd)
    assert done.returncode == 0, done.stderr
    assert "report: armkit-demo/report.html" in done.stdout
    assert re.search(r"the tool is [0-9.]+ mm from the target", done.stdout)
    out = cwd / "armkit-demo"
    for name in ("report.html", "summary.json", "plotly.min.js", "joints.png", "tool_path.png"):
        assert (out / name).is_file(), name
    return out


def test_the_report_references_nothing_outside_its_folder(demo_report):
    page = (demo_report / "report.html").read_text()
    refs = _References()
    refs.feed(page)
    assert "plotly.min.js" in refs.found and "joints.png" in refs.found
    for ref in refs.found:
        assert "://" not in ref and not ref.startswith(("/", "..")), ref
        assert (demo_report / ref).is_file(), ref


def _chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if path := shutil.which(name):
            return path
    raise AssertionError("no chromium: .ci/run installs Debian's chromium for this test")


def test_the_report_renders_in_a_headless_browser(demo_report, tmp_path):
    shot = tmp_path / "report.png"
    common = [_chromium(), "--headless", "--no-sandbox", "--disable-gpu",
              "--enable-unsafe-swiftshader", "--use-angle=swiftshader", "--no-first-run",
              f"--user-data-dir={tmp_path / 'profile'}", "--virtual-time-budget=15000",
              "--enable-logging=stderr", "--v=0", "--window-size=1200,1600"]
    url = (demo_report / "report.html").as_uri()
    dom = subprocess.run([*common, "--dump-dom", url], capture_output=True, text=True,
                         timeout=180)
    assert dom.returncode == 0, dom.stderr[-2000:]
    # plotly drew the 3-D scene (a WebGL canvas inside its scene container) and the controls.
    assert 'class="plot-container plotly"' in dom.stdout
    assert "gl-container" in dom.stdout and "<canvas" in dom.stdout
    assert "updatemenu" in dom.stdout and "slider" in dom.stdout
    console = [line for line in dom.stderr.splitlines() if "CONSOLE" in line]
    assert not [line for line in console if "rror" in line or "Uncaught" in line], console
    pic = subprocess.run([*common, f"--screenshot={shot}", url], capture_output=True,
                         text=True, timeout=180)
    assert pic.returncode == 0 and shot.stat().st_size > 50_000


def test_bad_task_file_is_one_line_and_sends_nothing(tmp_path):
    bad = tmp_path / "bad.task.yaml"
    bad.write_text((EXAMPLES / "water_supply.task.yaml").read_text().replace(
        "waypoints: 10", "waypoints: ten"))
    done = armkit("run", str(bad), "--out", str(tmp_path / "r"))
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0
    assert "motion.waypoints" in done.stderr and str(bad) in done.stderr
    assert not (tmp_path / "r" / "report.html").exists()


def test_an_unreachable_target_exits_1_with_a_report_that_says_so(tmp_path):
    far = tmp_path / "far.task.yaml"
    far.write_text((EXAMPLES / "water_supply.task.yaml").read_text().replace(
        "target: {xyz: [500, 400, 1400]", "target: {xyz: [5500, 400, 1400]"))
    done = armkit("run", str(far), "--out", str(tmp_path / "r"), "--json")
    assert done.returncode == 1
    doc = json.loads(done.stdout)
    assert doc["stopped_at"] == "ik" and "out of reach" in doc["reason"] and doc["sent"] is None
    assert "out of reach" in (tmp_path / "r" / "report.html").read_text()


@pytest.mark.parametrize("args, words", [
    (["run", "nowhere.yaml"], "nowhere.yaml"),
    (["run", str(EXAMPLES / "water_supply.task.yaml"), "--out", "/proc/armkit"], "--out"),
    (["view", "ur5", "0", "0"], "Q: expected 6 joint values for ur5, found 2"),
    (["view", "ur5", "0", "0", "0", "0", "0", "x"], "Q: expected a number"),
    (["view", "ur5", "--out", "view.png"], "--out"),
    (["view", "nobot"], "nobot"),
])
def test_bad_arguments_are_one_line(args, words, tmp_path):
    done = armkit(*args, cwd=tmp_path)
    assert done.returncode == 2, done.stdout
    assert done.stderr.strip().count("\n") == 0 and words in done.stderr
    assert "Traceback" not in done.stderr


def test_view_writes_one_offline_page(tmp_path):
    out = tmp_path / "ur5.html"
    done = armkit("view", "ur5", "0", "-90", "90", "-90", "-90", "0", "--out", str(out))
    assert done.returncode == 0, done.stderr
    page = out.read_text()
    refs = _References()
    refs.feed(page)
    assert not [r for r in refs.found if "://" in r]
    assert "Mesh3d" in page or "mesh3d" in page
