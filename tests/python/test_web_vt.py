"""The browser client's virtual texture (python/gigascroll/web/vt/) against the C++ core, in
headless chromium with WebGL2 on SwiftShader: the GPU sampler against VirtualTexture.sample
on the same resident set, the GPU feedback pass against render_view's at the same size, and
the request hash against HashProcessor.slot."""

import numpy as np
import pytest

import gigascroll as g
from browser import browser, chromium_path, open_page, serve_pack  # noqa: F401 - fixtures

TILE, BORDER = 128, 4
SIZES = [(4000, 300), (1500, 900)]  # a long one with four tail levels, a squarer one
SLOTS = (20, 20)                    # holds every tile of both: no eviction unless asked


@pytest.fixture(scope="module")
def vt_pack(tmp_path_factory):
    """Two paintings of smooth colour plus noise (bilinear weights matter at every texel)."""
    rng = np.random.default_rng(39)
    images = []
    for w, h in SIZES:
        y, x = np.mgrid[0:h, 0:w]
        base = np.stack([x * 255 // w, y * 255 // h, (x + y) % 256], axis=-1)
        noise = rng.integers(-40, 41, (h, w, 3))
        images.append(np.clip(base + noise, 0, 255).astype(np.uint8))
    path = tmp_path_factory.mktemp("web_vt") / "vt.pack"
    g.build_pack(images, path, tile_size=TILE, border=BORDER)
    return path


@pytest.fixture(scope="module")
def vt_page(browser, vt_pack):  # noqa: F811
    """The test page on a server of the pack, its virtual texture made (tails resident)."""
    with serve_pack(vt_pack) as url:
        page = open_page(browser, f"{url}/client/vt/test/harness.html", "window.vtTestReady === true")
        info = page.evaluate("(slots) => vtTest.init({slots})", list(SLOTS))
        yield page, info
        page.close()


def streamed_tiles(pack, rng, fraction):
    """A random `fraction` of the tiles of each painting's merged (unpinned) levels, shuffled."""
    keys = []
    for p, q in enumerate(pack.paintings):
        geo = g.PaintingGeometry(q.width, q.height, TILE, BORDER)
        merged = min(int(np.log2(min(q.table_size))) + 1, q.levels)
        for l in range(min(merged, q.levels - 1)):
            for ty in range(geo.tiles_y(l)):
                for tx in range(geo.tiles_x(l)):
                    if rng.random() < fraction:
                        keys.append((p, l, tx, ty))
    rng.shuffle(keys)
    return keys


def probes(pack, rng, n):
    """n probes (painting, u, v, lod) per painting, float32 as the GPU gets them: u, v a little
    beyond [0, 1] (clamp to edge), lod over every level and past the top, a fifth of them
    whole (bilinear at one level), the rest fractional (trilinear)."""
    out = []
    for p, q in enumerate(pack.paintings):
        uv = rng.uniform(-0.02, 1.02, (n, 2))
        lod = rng.uniform(0, q.levels - 0.5, n)
        whole = rng.random(n) < 0.2
        lod[whole] = np.floor(lod[whole])
        out.append(np.column_stack([np.full(n, p), uv, lod]))
    return np.concatenate(out).astype(np.float32)


def cpu_samples(vt, pr):
    """VirtualTexture.sample (trilinear) at the probes, and the level that answered."""
    rgb = np.zeros((len(pr), 3), np.float32)
    level = np.zeros(len(pr), np.int8)
    for p in np.unique(pr[:, 0]).astype(int):
        m = pr[:, 0] == p
        rgb[m], level[m] = vt.sample(p, pr[m, 1].astype(np.float64), pr[m, 2].astype(np.float64),
                                     pr[m, 3], filter="trilinear")
    return rgb, level


def test_gpu_sampler_equals_core_sampler(vt_page, vt_pack):
    """The GPU's vtSample equals the core's trilinear sample through the same page table
    (fallbacks included) within 2/255: float32 positions against the core's doubles move the
    weights by ~1e-4 texel here (sampler.glsl.js says where)."""
    page, info = vt_page
    pack = g.TilePack(str(vt_pack))
    rng = np.random.default_rng(5)
    vt = g.VirtualTexture(pack, slots=SLOTS)
    assert info["pinned"] == vt.stats()["pinned"] and tuple(info["slots"]) == SLOTS
    keys = streamed_tiles(pack, rng, 0.45)
    for k in keys:
        vt.insert(k, pack.read_tile(*k))
    assert page.evaluate("(keys) => vtTest.insertTiles(keys)", [list(k) for k in keys]) == vt.stats()["resident"]
    pr = probes(pack, rng, 1500)
    gpu = np.asarray(page.evaluate("(p) => vtTest.sampleProbes(p)", pr.ravel().tolist()),
                     np.float32).reshape(-1, 4)
    cpu, level = cpu_samples(vt, pr)
    # The probes exercise the fallback: some answer from a coarser level than asked.
    assert (level > np.floor(np.clip(pr[:, 3], 0, None))).mean() > 0.2
    diff = np.abs(gpu[:, :3] * 255 - cpu)
    assert diff.max() <= 2.0, f"max {diff.max():.3f} at probe {pr[diff.max(axis=1).argmax()]}"
    assert np.all(gpu[:, 3] == 1)


def test_gpu_sampler_after_evictions(vt_pack, browser):  # noqa: F811
    """A cache smaller than the tiles inserted: the same LRU evicts the same tiles on both
    sides (the evicted tiles' entries fall back to their parents), and the samples agree."""
    pack = g.TilePack(str(vt_pack))
    rng = np.random.default_rng(11)
    slots = (8, 6)
    vt = g.VirtualTexture(pack, slots=slots)
    keys = streamed_tiles(pack, rng, 0.8)
    keys += keys[: len(keys) // 3]  # re-inserting a resident tile makes it most recent
    for k in keys:
        vt.insert(k, pack.read_tile(*k))
    assert vt.stats()["evictions"] > 50
    with serve_pack(vt_pack) as url:
        page = open_page(browser, f"{url}/client/vt/test/harness.html")
        page.evaluate("(slots) => vtTest.init({slots})", list(slots))
        page.evaluate("(keys) => vtTest.insertTiles(keys)", [list(k) for k in keys])
        assert page.evaluate("() => vt.cache.stats.evictions") == vt.stats()["evictions"]
        pr = probes(pack, rng, 800)
        gpu = np.asarray(page.evaluate("(p) => vtTest.sampleProbes(p)", pr.ravel().tolist()),
                         np.float32).reshape(-1, 4)
        page.close()
    cpu, _ = cpu_samples(vt, pr)
    assert np.abs(gpu[:, :3] * 255 - cpu).max() <= 2.0
