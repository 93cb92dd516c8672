"""Sharded pack builds (gigascroll.pack.shards): on a 2-worker Dask LocalCluster and on a
process pool the pack is byte for byte, entry for entry and tile for tile the single-process
build's; a lost worker or a failing painting leaves no pack; resume reuses exactly the shards
that were completed and still verify."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from gigascroll import TilePack, build_pack
from gigascroll.pack.reader import _ENTRY

distributed = pytest.importorskip("dask.distributed")

SIZES = [(300, 200), (130, 90), (500, 60), (70, 70), (33, 150)]


@pytest.fixture(scope="module")
def images():
    rng = np.random.default_rng(5)
    out = []
    for w, h in SIZES:
        a = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
        a[h // 3:h // 2] = 90  # compressible rows
        out.append(a)
    return out


@pytest.fixture(scope="module")
def cluster():
    """One 2-worker LocalCluster for the module (its startup is the slow part). A lost worker
    fails its task at once (allowed-failures 0) instead of being retried on the other."""
    import dask
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        from gigascroll.pack.shards import local_cluster
        with local_cluster(2) as c:
            yield c


@pytest.fixture(scope="module")
def single(images, tmp_path_factory):
    return build_pack(images, tmp_path_factory.mktemp("single") / "p", tile_size=32, border=2,
                      codec="zstd")


def _entries(path):
    return np.frombuffer((path / "index.bin").read_bytes(), _ENTRY, offset=32)


def assert_same_pack(a, b):
    from pathlib import Path
    pa, pb = Path(a.path), Path(b.path)
    assert sorted(os.listdir(pa)) == sorted(os.listdir(pb))  # no shard leftovers
    for name in os.listdir(pa):  # manifest, index.bin and every tile file
        assert (pa / name).read_bytes() == (pb / name).read_bytes(), name
    assert np.array_equal(_entries(pa), _entries(pb))
    for i, p in enumerate(a.paintings):
        for l, (nx, ny) in enumerate(p.level_tiles):
            for ty in range(ny):
                for tx in range(nx):
                    assert np.array_equal(a.read_tile(i, l, tx, ty), b.read_tile(i, l, tx, ty))


def test_two_dask_workers_build_the_single_process_pack(images, single, cluster, tmp_path):
    sharded = build_pack(images, tmp_path / "p", tile_size=32, border=2, codec="zstd",
                         scheduler=cluster.scheduler_address)
    assert sharded.tile_files == [f"tiles-{i:05d}.bin" for i in range(len(SIZES))]
    assert_same_pack(single, sharded)
    assert not (tmp_path / "p.shards").exists()


def test_process_pool_builds_the_same_pack(images, single, tmp_path):
    sharded = build_pack(images, tmp_path / "p", tile_size=32, border=2, codec="zstd",
                         workers=2, executor="processes")
    assert_same_pack(single, sharded)


def test_lost_worker_leaves_no_pack_and_resume_reuses_verified_shards(images, single, cluster,
                                                                      tmp_path):
    log = tmp_path / "built.log"
    bad = 2

    def hook(index, name):  # runs on the worker; pickled by value
        import os
        import time
        if index == bad and not os.path.exists(str(log) + ".healed"):
            time.sleep(2.0)  # the other worker finishes the rest meanwhile
            os._exit(3)      # the worker process dies mid-build
        with open(log, "a") as f:
            f.write(f"{index}\n")

    out = tmp_path / "p"
    with pytest.raises(OSError, match="worker was lost.*painting2.*--resume"):
        build_pack(images, out, tile_size=32, border=2, codec="zstd",
                   scheduler=cluster.scheduler_address, shard_hook=hook)
    assert not out.exists()
    shards = tmp_path / "p.shards"
    done = {i for i in range(len(SIZES)) if (shards / f"shard-{i:05d}.json").exists()}
    assert bad not in done and len(done) >= 1
    # A completed shard whose tile file was damaged since must be rebuilt, not reused.
    damaged = min(done)
    tiles = shards / f"tiles-{damaged:05d}.bin"
    data = bytearray(tiles.read_bytes())
    data[40] ^= 0xFF
    tiles.write_bytes(data)

    (tmp_path / "built.log.healed").write_text("")
    log.write_text("")
    resumed = build_pack(images, out, tile_size=32, border=2, codec="zstd",
                         scheduler=cluster.scheduler_address, shard_hook=hook, resume=True)
    rebuilt = {int(x) for x in log.read_text().split()}
    assert rebuilt == set(range(len(SIZES))) - done | {damaged}
    assert_same_pack(single, resumed)


def test_failing_painting_fails_the_build_cleanly(images, cluster, tmp_path):
    def hook(index, name):
        if index == 1:
            raise ValueError(f"painting {name} is unreadable")

    with pytest.raises(ValueError, match="painting1 is unreadable") as e:
        build_pack(images, tmp_path / "p", tile_size=32, border=2,
                   scheduler=cluster.scheduler_address, shard_hook=hook)
    assert any("--resume" in n for n in getattr(e.value, "__notes__", []))
    assert not (tmp_path / "p").exists()
    # resume needs a sharded build; bad worker counts are refused before any work
    with pytest.raises(ValueError, match="resume"):
        build_pack(images, tmp_path / "q", resume=True)
    with pytest.raises(ValueError, match="workers"):
        build_pack(images, tmp_path / "q", workers=-1)
    with pytest.raises(ValueError, match="scheduler"):
        build_pack(images, tmp_path / "q", scheduler="not an address")


def test_pack_works_without_dask(tmp_path):
    """Without dask importable, a single-process build works and never imports it; a sharded
    build asks for the cluster extra."""
    code = f"""
import sys, numpy as np
sys.modules['dask'] = None; sys.modules['dask.distributed'] = None; sys.modules['distributed'] = None
import gigascroll
img = np.zeros((40, 50, 3), np.uint8)
p = gigascroll.build_pack(img, {str(tmp_path / 'a')!r}, tile_size=16, border=2)
assert p.tile_count > 0
try:
    gigascroll.build_pack(img, {str(tmp_path / 'b')!r}, tile_size=16, border=2, workers=2)
except ValueError as e:
    assert "cluster" in str(e), e
    print("ok")
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr[-2000:]
    assert not (tmp_path / "b").exists()
    assert json.loads((tmp_path / "a" / "manifest.json").read_text())["version"] == 2


def test_cli_pack_on_a_scheduler_and_resume_misuse(images, single, cluster, tmp_path):
    from gigascroll.cli import main
    from gigascroll.pack.synth import synth_painting
    src = tmp_path / "a.tif"
    synth_painting(src, 300, 80)
    assert main(["pack", str(src), "-o", str(tmp_path / "p"), "--tile-size", "32", "--border",
                 "2", "--scheduler", cluster.scheduler_address]) == 0
    one = TilePack(tmp_path / "p")
    ref = build_pack(str(src), tmp_path / "ref", tile_size=32, border=2)
    assert_same_pack(ref, one)
    assert main(["pack", str(src), "-o", str(tmp_path / "q"), "--resume"]) == 2
    assert main(["pack", str(src), "-o", str(tmp_path / "q"), "--workers", "-3"]) == 2
    assert not (tmp_path / "q").exists()
