"""`armkit run`, `armkit demo` and `armkit view` as users run them: real processes, the
simulated drive on an ephemeral port, the report opened alone in a real headless browser, and
outputs that cannot be written found before anything moves (or, after, exit 3)."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import pytest
import yaml

from tests.report.browser import Browser

pytestmark = pytest.mark.slow      # commands run as users run them: CI runs them all

ROOT = Path(__file__).parents[2]
EXAMPLES = ROOT / "examples" / "tasks"
TASKS = sorted(EXAMPLES.glob("*.task.yaml"))
ROBOTS = ROOT / "src" / "armkit" / "model" / "robots"


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
    done = 0
    for name, job in jobs.items():
        out, err = job.communicate(timeout=600)
        doc = json.loads(out)
        if doc["stopped_at"] == "plan" and doc["reason"].startswith(
                "no collision-free path: no path within the time limit"):
            # Five jobs planning at once on a loaded machine may spend a task's time limit:
            # an honest result, with nothing sent.
            assert job.returncode == 1 and doc["sent"] is None, name
            continue
        assert job.returncode == 0, f"{name}: {doc['reason']} {err}"
        assert doc["success"] and doc["reason"] == "ok", name
        done += 1
        assert doc["sent"]["last_accepted"] == len(doc["waypoints"]["q"]) - 1, name
        assert doc["position_error"]["m"] <= doc["position_error"]["drive_resolution_m"], name
        assert json.loads((tmp_path / name / "summary.json").read_text())["success"], name
    assert done >= 1


class _References(HTMLParser):
    def __init__(self):
        super().__init__()
        self.found: list[str] = []
        self.scripts = 0

    def handle_starttag(self, tag, attrs):
        self.scripts += tag == "script"
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
    assert sorted(p.name for p in out.iterdir()) == ["joints.png", "report.html",
                                                    "summary.json", "tool_path.png",
                                                    "torques.png"]
    return out


def test_the_report_holds_everything_it_shows(demo_report):
    page = (demo_report / "report.html").read_text()
    refs = _References()
    refs.feed(page)
    # The figures (joints, torques, tool path) are data URIs; no script, style or picture
    # comes from anywhere else.
    assert len([r for r in refs.found if r.startswith("data:image/png;base64,")]) == 3
    assert all(r.startswith("data:") for r in refs.found), refs.found
    assert page.count("plotly.js v") == 1 or page.count("* plotly.js") == 1


def test_the_report_opens_alone_in_a_headless_browser(demo_report, tmp_path):
    """Copied into an empty folder (as when mailed), opened with no network: the 3-D view is
    drawn (a WebGL canvas in plotly's scene), the figures are decoded, and the page logs no
    error."""
    alone = tmp_path / "mailed"
    alone.mkdir()
    shutil.copy(demo_report / "report.html", alone / "report.html")
    with Browser((alone / "report.html").as_uri(), tmp_path / "profile", (1300, 3000)) as page:
        page.wait_for("document.querySelector('#view3d .gl-container canvas') !== null")
        assert page.wait_for("Array.from(document.images).every((i) => i.complete) && "
                             "Array.from(document.images).map((i) => i.naturalWidth)")[0] > 500
        assert page.evaluate("typeof Plotly") == "object"
        assert page.evaluate("document.querySelectorAll('#view3d .slider-container').length")
        page.screenshot(tmp_path / "report.png")
        log = page.close()
    errors = [line for line in log.splitlines() if "CONSOLE" in line and
              ("rror" in line or "Uncaught" in line)]
    assert not errors, errors
    assert (tmp_path / "report.png").stat().st_size > 50_000


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


@pytest.mark.parametrize("blocked", ["report.html", "summary.json", "joints.png"])
def test_an_output_that_cannot_be_written_is_refused_before_the_job(blocked, tmp_path):
    out = tmp_path / "r"
    (out / blocked).mkdir(parents=True)              # a directory where a file must go
    done = armkit("demo", "--out", str(out))
    assert done.returncode == 2, done.stdout
    assert done.stderr.strip().count("\n") == 0 and "--out" in done.stderr
    assert blocked in done.stderr and "Traceback" not in done.stderr
    assert "waypoints" not in done.stdout              # the job did not start
    assert sorted(p.name for p in out.iterdir()) == [blocked]


def test_a_record_that_fails_after_the_motion_exits_3(tmp_path):
    """The report's page becomes unwritable while the arm moves: the motion is done, the
    summary and the figures are written, the page is not; one line says so, exit 3."""
    out = tmp_path / "r"
    job = subprocess.Popen([sys.executable, "-m", "armkit", "demo", "--out", str(out)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    for line in job.stdout:
        if "checks before sending" in line:
            (out / "report.html").mkdir()            # while the waypoints go out
            break
    rest, err = job.communicate(timeout=300)
    assert job.returncode == 3, (rest, err)
    assert err.strip().count("\n") == 0 and "Traceback" not in err
    assert err.startswith("the motion is done (ok), but its record is incomplete: ")
    assert "report.html" in err and "written: summary.json, joints.png, torques.png, tool_path.png" in err
    assert json.loads((out / "summary.json").read_text())["success"]


def test_names_from_files_reach_the_report_as_text(tmp_path):
    """A robot, a joint, an obstacle and a task named with math markup, HTML and console
    markup: the job runs, its figures draw, its page shows the names as text."""
    robot = yaml.safe_load((ROBOTS / "water_supply.yaml").read_text())
    robot["name"] = "ws$\\frac{$"
    robot["joints"][1]["name"] = "lift$^$"
    (tmp_path / "arm.yaml").write_text(yaml.safe_dump(robot))
    task = yaml.safe_load((EXAMPLES / "water_supply.task.yaml").read_text())
    task.update(name=":x: [bold]<script>alert(1)</script>", robot="arm.yaml")
    task["scene"]["obstacles"][0]["name"] = "<a href='https://example.com'>post</a> $x$"
    (tmp_path / "t.task.yaml").write_text(yaml.safe_dump(task))
    done = armkit("run", "t.task.yaml", "--out", "r", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert ":x: [bold]<script>alert(1)</script>" in done.stdout     # printed as written
    # The page's body (its head holds plotly's own script); its JSON writes "/" as "\u002f".
    page = (tmp_path / "r" / "report.html").read_text().split("</head>", 1)[1]
    page = page.replace("\\u002f", "/")
    assert "<script>alert(1)</script>" not in page and "<a href=" not in page
    assert "&lt;a href=&#x27;https://example.com&#x27;&gt;post&lt;/a&gt; &#36;x&#36;" in page
    for figure in ("joints.png", "torques.png", "tool_path.png"):
        assert (tmp_path / "r" / figure).stat().st_size > 10_000


@pytest.mark.parametrize("args, words", [
    (["run", "nowhere.yaml"], "nowhere.yaml"),
    (["run", str(EXAMPLES / "water_supply.task.yaml"), "--out", "/proc/armkit"], "--out"),
    (["view", "ur5", "0", "0"], "Q: expected 6 joint values for ur5, found 2"),
    (["view", "ur5", "0", "0", "0", "0", "0", "x"], "Q: expected a number"),
    (["view", "ur5", "--out", "view.png"], "--out"),
    (["view", "ur5", "--out", "/proc/view.html"], "--out"),
    (["view", "nobot"], "nobot"),
    (["view", "water_supply", "5000", "0", "0", "0"],
     "Q: expected lift within 0..600 mm, found 5000"),
    (["view", "ur5", "--tip", "tool0"], "tip: expected none for a robot file"),
    (["view", "ur5", "--tip"], "--tip"),
])
def test_bad_arguments_are_one_line(args, words, tmp_path):
    done = armkit(*args, cwd=tmp_path)
    assert done.returncode == 2, done.stdout
    assert done.stderr.strip().count("\n") == 0 and words in done.stderr
    assert "Traceback" not in done.stderr


def test_view_writes_one_page_with_joint_sliders(tmp_path):
    out = tmp_path / "ur5.html"
    done = armkit("view", "ur5", "0", "-90", "90", "-90", "-90", "0", "--out", str(out))
    assert done.returncode == 0, done.stderr
    page = out.read_text()
    refs = _References()
    refs.feed(page)
    assert not refs.found                            # nothing loaded from anywhere
    assert page.count('type="range"') == 6 and 'id="tool-pose"' in page
    assert 'value="-90"' in page
