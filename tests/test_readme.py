"""The README's quick start stays true: two command lines, and CI runs the test one."""

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def quick_start() -> list[str]:
    text = (ROOT / "README.md").read_text()
    block = text.split("## Quick start", 1)[1].split("```", 2)[1]
    return [line for line in block.splitlines() if line.strip()]


def test_quick_start_is_two_lines_demo_and_tests():
    lines = quick_start()
    assert len(lines) == 2
    assert lines[0].endswith("armkit demo") and "pytest" in lines[1]


def test_ci_runs_the_readme_test_command():
    assert quick_start()[1] in (ROOT / ".ci" / "run").read_text().splitlines()


def python_blocks() -> list[str]:
    text = (ROOT / "README.md").read_text()
    return [block.split("\n", 1)[1] for block in text.split("```")[1::2]
            if block.startswith("python\n")]


def test_the_tour_and_the_cartesian_example_run_as_written():
    blocks = python_blocks()
    tour = next(b for b in blocks if "ur5 = armkit.robot(\"ur5\")" in b)
    line = next(b for b in blocks if "cartesian_line" in b)
    namespace: dict = {}
    exec(compile(tour, "README.md: A tour", "exec"), namespace)
    exec(compile(line, "README.md: Cartesian motion", "exec"), namespace)
    path = namespace["path"]
    assert path.success and path.reason == "ok" and path.stop == 1.0
    assert namespace["timed"].duration > 0
