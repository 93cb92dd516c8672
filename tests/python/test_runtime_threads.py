"""The tile loader and the cache used from several Python threads at once, against direct
reads of the pack, and a cache refusing a loader of another pack."""
import threading
import time

import numpy as np
import pytest

from gigascroll import TileLoader, VirtualTexture, build_pack

T, B = 16, 2


@pytest.fixture(scope="module")
def packs(tmp_path_factory):
    root = tmp_path_factory.mktemp("threads")
    rng = np.random.default_rng(11)
    a = build_pack(rng.integers(0, 256, (90, 130, 3), dtype=np.uint8), root / "a", tile_size=T, border=B)
    # Same geometry, other texels: a loader of it must not feed a's cache.
    b = build_pack(rng.integers(0, 256, (90, 130, 3), dtype=np.uint8), root / "b", tile_size=T, border=B)
    return a, b


def all_keys(pack):
    p = pack.paintings[0]
    return [(0, l, tx, ty) for l, (nx, ny) in enumerate(p.level_tiles) for ty in range(ny) for tx in range(nx)]


@pytest.mark.parametrize("mode,threads", [("lockfree", 2), ("locked", 2)])
def test_python_threads_hammering_one_loader_get_every_tile_once(packs, mode, threads):
    """Four Python threads submit, poll and read stats on one loader at once, then a fifth
    closes it: every tile comes back exactly as often as it was asked for, with the bytes of
    a direct read, the backlog ends at zero and close() returns."""
    pack = packs[0]
    keys = all_keys(pack)
    callers, copies = 4, 3
    expected = len(keys) * copies * callers
    got = [[] for _ in range(callers)]
    errors = []
    loader = TileLoader(pack, mode, threads, queue_capacity=8, pool_tiles=4)
    total = [0]
    lock = threading.Lock()

    def caller(c):
        try:
            for _ in range(copies):
                for i in range(0, len(keys), 5):
                    loader.submit(np.array(keys[i:i + 5]))
            deadline = time.monotonic() + 60
            while time.monotonic() < deadline:
                with lock:
                    if total[0] >= expected:
                        return
                batch = loader.poll(max_tiles=3)
                loader.stats()
                got[c] += batch
                with lock:
                    total[0] += len(batch)
                if not batch:
                    time.sleep(0.0005)
        except Exception as e:  # reported below, with the thread's index
            errors.append((c, e))

    threads_ = [threading.Thread(target=caller, args=(c,)) for c in range(callers)]
    for t in threads_:
        t.start()
    for t in threads_:
        t.join(120)
        assert not t.is_alive(), "a caller hung"
    assert not errors, errors
    closer = threading.Thread(target=loader.close)
    closer.start()
    closer.join(30)
    assert not closer.is_alive(), "close() hung"
    assert loader.closed
    delivered = [item for per in got for item in per]
    assert len(delivered) == expected
    counts = {}
    for k, data in delivered:
        assert isinstance(data, np.ndarray), data
        np.testing.assert_array_equal(data, pack.read_tile(*k))
        counts[k] = counts.get(k, 0) + 1
    assert counts == {k: copies * callers for k in keys}
    s = loader.stats()
    assert (s["submitted"], s["loaded"], s["backlog"], s["cancelled"]) == (expected, expected, 0, 0)


def test_drain_from_several_threads_loses_no_tile(packs):
    pack = packs[0]
    keys = all_keys(pack)
    vt = VirtualTexture(pack, slots=(16, 16))
    arrived = []
    with TileLoader(pack, "lockfree", 2, queue_capacity=8, pool_tiles=4) as loader:
        loader.submit(np.array(keys))

        def drainer():
            deadline = time.monotonic() + 60
            while sum(len(a) for a in arrived) < len(keys) and time.monotonic() < deadline:
                a, failed = vt.drain(loader, max_tiles=2)
                assert not failed
                arrived.append(a)
                time.sleep(0.0002)

        ts = [threading.Thread(target=drainer) for _ in range(3)]
        for t in ts:
            t.start()
        for t in ts:
            t.join(120)
    got = np.concatenate(arrived) if arrived else np.array([], np.uint64)
    assert len(got) == len(keys) and len(set(got.tolist())) == len(keys)
    assert vt.page_table_matches_rebuild()
    for k in keys:
        if vt.is_resident(k):  # what the cache holds is the pack's tile
            level, slot = vt.lookup(k)
            if level == k[1]:
                np.testing.assert_array_equal(vt.physical[slot], pack.read_tile(*k))


def test_drain_refuses_a_loader_of_another_pack(packs):
    a, b = packs
    vt = VirtualTexture(a, slots=(16, 16))
    with TileLoader(b, "lockfree", 1) as loader:
        loader.submit(np.array(all_keys(b)[:4]))
        with pytest.raises(ValueError, match="another pack"):
            vt.drain(loader)
        # Nothing was polled: the tiles are still there for a drain into b's own cache.
        vt_b = VirtualTexture(b, slots=(16, 16))
        deadline = time.monotonic() + 30
        arrived = []
        while len(arrived) < 4 and time.monotonic() < deadline:
            arrived += list(vt_b.drain(loader)[0])
            time.sleep(0.001)
        assert len(arrived) == 4
    # A second opened copy of a is the same pack: accepted.
    from gigascroll import TilePack
    with TileLoader(TilePack(a.path), "locked", 1) as loader:
        loader.submit(np.array(all_keys(a)[:2]))
        deadline = time.monotonic() + 30
        n = 0
        while n < 2 and time.monotonic() < deadline:
            arrived, failed = vt.drain(loader)
            assert not failed
            n += len(arrived)
            time.sleep(0.001)
        assert n == 2
