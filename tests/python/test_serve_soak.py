"""Eight clients on loopback fetching random tiles (single and batch) from a `gigascroll serve`
subprocess for 20 s (GIGASCROLL_SERVE_SOAK_SECONDS sets another duration): every byte equals
the pack's (`TilePack.read_tile`), no request fails, and the server's resident memory (from
/proc) stays within a bound while it serves many times its bound in bytes."""

from __future__ import annotations

import http.client
import json
import os
import re
import threading
import time
import urllib.parse

import numpy as np
from serve_support import ServeProcess, scene_of

from gigascroll import build_pack
from gigascroll.experiments import pattern_image

CLIENTS = 8
SECONDS = float(os.environ.get("GIGASCROLL_SERVE_SOAK_SECONDS", "20"))
RSS_GROWTH_BOUND_MIB = 96   # the server's bound: 16 requests of 64 tiles in flight, ~50 MB


def client(url, h, expected, keys, seed, stop, results):
    rng = np.random.default_rng(seed)
    u = urllib.parse.urlsplit(url)
    conn = http.client.HTTPConnection(u.hostname, u.port, timeout=60)
    done = nbytes = 0
    errors = []
    try:
        while not stop.is_set():
            if rng.random() < 0.5:
                k = keys[rng.integers(len(keys))]
                conn.request("GET", f"/api/tiles/{h}/{k[0]}/{k[1]}/{k[2]}/{k[3]}")
                want = expected[k]
            else:
                chosen = [keys[i] for i in rng.integers(0, len(keys), rng.integers(1, 65))]
                conn.request("POST", f"/api/tiles/{h}/batch", json.dumps({"keys": chosen}),
                             {"Content-Type": "application/json"})
                want = b"".join(expected[k] for k in chosen)
            r = conn.getresponse()
            body = r.read()
            if r.status != 200 or body != want:
                errors.append((r.status, len(body), len(want)))
            done += 1
            nbytes += len(body)
    except Exception as e:  # noqa: BLE001 (reported by the test)
        errors.append(repr(e))
    finally:
        conn.close()
    results.append((done, nbytes, errors))


def test_eight_clients_get_every_byte_with_bounded_memory(tmp_path):
    pack = build_pack(pattern_image(4000, 600), tmp_path / "p.pack")
    keys = [(0, level, x, y) for level, (nx, ny) in enumerate(pack.paintings[0].level_tiles)
            for x in range(nx) for y in range(ny)]
    expected = {k: pack.read_tile(*k).tobytes() for k in keys}
    with ServeProcess([pack.path, "--room", "scroll", "--port", "0",
                       "--cache-dir", tmp_path / "cache"], tmp_path) as server:
        h = scene_of(server.url)["pack"]["hash"]
        stop, results, rss = threading.Event(), [], []
        threads = [threading.Thread(target=client, args=(server.url, h, expected, keys, s, stop,
                                                         results)) for s in range(CLIENTS)]
        for t in threads:
            t.start()
        t0 = time.monotonic()
        while time.monotonic() - t0 < SECONDS:
            rss.append(server.rss_kib())
            time.sleep(0.2)
        stop.set()
        for t in threads:
            t.join(120)
        assert server.stop() == 0
        log = server.stderr()
    requests = sum(r[0] for r in results)
    served_mib = sum(r[1] for r in results) / 2**20
    errors = [e for r in results for e in r[2]]
    assert len(results) == CLIENTS and errors == []
    assert requests > 50 * CLIENTS * min(SECONDS, 1)
    # Memory: after the first second's warm-up, at most the bound above it, while the
    # clients fetched far more than the bound (a per-request leak would show).
    warm = rss[min(5, len(rss) - 1)]
    growth_mib = (max(rss) - warm) / 1024
    assert growth_mib < RSS_GROWTH_BOUND_MIB, (rss[:10], max(rss))
    assert served_mib > 2 * RSS_GROWTH_BOUND_MIB or SECONDS < 5
    assert "Traceback" not in log and not re.search(r"serve: [45]\d\d ", log), log
    print(f"{requests} requests, {served_mib:.0f} MiB in {SECONDS:g} s; server RSS "
          f"{warm / 1024:.0f} -> max {max(rss) / 1024:.0f} MiB")
