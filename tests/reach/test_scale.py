"""Maps at scale: the same bits on one thread, on several, on a Dask cluster of worker
processes, and after an interruption resumed from the finished chunks."""

from __future__ import annotations

import numpy as np
import pytest

import armkit
from armkit.io.reach_maps import ChunkFolder
from armkit.reach import Orientations, reach_map

pytestmark = pytest.mark.slow      # commands run as users run them: CI runs them all

FIELDS = ("voxels", "count", "reached", "manipulability")


def assert_same_map(a, b):
    for name in FIELDS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and np.array_equal(x, y), name
    assert a.settings["key"] == b.settings["key"]


# A closed-form map, and a numeric one whose random restarts are seeded per chunk.
CASES = {"ur5": dict(resolution=0.2, orientations=Orientations.sphere(16), samples=100_000,
                     chunk=40),
         "panda": dict(resolution=0.3, orientations=Orientations.sphere(4), samples=100_000,
                       restarts=2, chunk=25)}


@pytest.mark.parametrize("name", CASES)
def test_threads_give_the_same_bits(name):
    robot = armkit.robot(name)
    one = reach_map(robot, threads=1, **CASES[name])
    two = reach_map(robot, threads=2, **CASES[name])
    assert_same_map(one, two)
    assert one.count.sum() > 0


@pytest.mark.parametrize("name", CASES)
def test_dask_gives_the_local_bits(dask_client, name):
    robot = armkit.robot(name)
    local = reach_map(robot, threads=1, **CASES[name])
    remote = reach_map(robot, scheduler=dask_client.scheduler.address, **CASES[name])
    assert_same_map(local, remote)
    seen = []
    again = reach_map(robot, scheduler=dask_client, progress=lambda d, n: seen.append((d, n)),
                      **CASES[name])
    assert_same_map(local, again)
    assert seen[-1] == (len(local.voxels), len(local.voxels)) and len(seen) > 2


class Interrupt(Exception):
    pass


def interrupting(after: int):
    """A progress callback that stops the run once `after` voxels are done."""
    def progress(done, total):
        if done >= after:
            raise Interrupt
    return progress


@pytest.mark.parametrize("where", ["local", "dask"])
def test_an_interrupted_map_resumes_from_its_finished_chunks(tmp_path, where, request):
    robot = armkit.robot("ur5")
    settings = CASES["ur5"]
    whole = reach_map(robot, threads=1, **settings)
    folder = ChunkFolder(tmp_path / "chunks")
    with pytest.raises(Interrupt):
        reach_map(robot, threads=1, checkpoint=folder, progress=interrupting(300), **settings)
    kept = sorted(p.name for p in folder.path.glob("chunk-*.npz"))
    assert 300 // 40 <= len(kept) < -(-len(whole.voxels) // 40)
    seen = []
    scheduler = request.getfixturevalue("dask_client") if where == "dask" else None
    resumed = reach_map(robot, threads=2, checkpoint=folder, scheduler=scheduler,
                        progress=lambda d, n: seen.append(d), **settings)
    assert folder.resumed == len(kept)
    assert seen[0] == len(kept) * 40                # the finished chunks, not solved again
    assert_same_map(whole, resumed)


def test_other_settings_start_the_folder_afresh(tmp_path):
    robot = armkit.robot("water_supply")
    folder = ChunkFolder(tmp_path / "chunks")
    reach_map(robot, 0.2, 6, checkpoint=folder, chunk=50)
    assert len(list(folder.path.glob("chunk-*.npz"))) > 5
    other = reach_map(robot, 0.2, 8, checkpoint=folder, chunk=50)
    assert folder.resumed == 0
    assert_same_map(other, reach_map(robot, 0.2, 8, chunk=50))


def test_a_damaged_chunk_is_solved_again(tmp_path):
    robot = armkit.robot("water_supply")
    folder = ChunkFolder(tmp_path / "chunks")
    whole = reach_map(robot, 0.2, 6, checkpoint=folder, chunk=50)
    (folder.path / "chunk-000003.npz").write_bytes(b"not a chunk")
    np.savez(folder.path / "chunk-000004.npz", count=np.zeros(3, np.int64))
    again = reach_map(robot, 0.2, 6, checkpoint=folder, chunk=50)
    assert folder.resumed == -(-len(whole.voxels) // 50) - 2
    assert_same_map(whole, again)
