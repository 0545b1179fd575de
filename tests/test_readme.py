"""The README's quick start stays true: two command lines, and CI runs the test one."""

from pathlib import Path

import pytest

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
    """Every ```python block of the README, in order."""
    parts = (ROOT / "README.md").read_text().split("```python\n")[1:]
    return [part.split("```", 1)[0] for part in parts]


@pytest.mark.slow
def test_readme_python_blocks_run_in_order(monkeypatch):
    """Each block runs as written, in one namespace, from the repository's root (the paths
    in the examples are relative to it); a block may use the names of the ones before it."""
    blocks = python_blocks()
    assert len(blocks) >= 5
    monkeypatch.chdir(ROOT)
    names: dict = {"__name__": "readme"}
    for number, block in enumerate(blocks, 1):
        code = compile(block, f"README.md python block {number}", "exec")
        exec(code, names)               # noqa: S102 - the README's own examples
