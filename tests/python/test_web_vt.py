"""The browser client's virtual texture (python/gigascroll/web/vt/) against the C++ core, in
headless chromium with WebGL2 on SwiftShader: the GPU sampler against VirtualTexture.sample
on the same resident set, the GPU feedback pass against render_view's at the same size, and
the request hash against HashProcessor.slot."""

import base64
import functools

import numpy as np
import pytest

import gigascroll as g
from browser import browser, chromium_path, open_page, pack_scene, serve_pack  # noqa: F401 - fixtures

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
        info = page.evaluate("([slots, scene]) => vtTest.init({slots, scene})",
                             [list(SLOTS), pack_scene(vt_pack)])
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


@pytest.mark.parametrize("hardware", [False, True], ids=["texelFetch", "hardware-bilinear"])
def test_gpu_sampler_equals_core_sampler(vt_page, vt_pack, hardware):
    """The GPU's vtSample equals the core's trilinear sample through the same page table
    (fallbacks included) within 2/255: float32 positions against the core's doubles move the
    weights by ~1e-4 texel here (sampler.glsl.js says where): 0.005 of a code measured. The
    hardware-bilinear variant adds the filter's weight rounding: 0.02 of a code on SwiftShader,
    up to about half a code on GPUs with 8-bit weight fractions."""
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
    gpu = np.asarray(page.evaluate("([p, hw]) => vtTest.sampleProbes(p, hw)", [pr.ravel().tolist(), hardware]),
                     np.float32).reshape(-1, 4)
    cpu, level = cpu_samples(vt, pr)
    # The probes exercise the fallback: some answer from a coarser level than asked.
    assert (level > np.floor(np.clip(pr[:, 3], 0, None))).mean() > 0.2
    diff = np.abs(gpu[:, :3] * 255 - cpu)
    assert diff.max() <= 2.0, f"max {diff.max():.3f} at probe {pr[diff.max(axis=1).argmax()]}"
    assert np.all(gpu[:, 3] == 1)


def test_gpu_sampler_after_evictions(vt_pack, browser):  # noqa: F811
    """A cache smaller than the tiles inserted, with a frame's requests between inserts: the
    same LRU (hits made most recent) evicts the same tiles into the same slots on both sides
    (the evicted tiles' entries fall back to their parents), and the samples agree."""
    pack = g.TilePack(str(vt_pack))
    rng = np.random.default_rng(11)
    slots = (8, 6)
    vt = g.VirtualTexture(pack, slots=slots)
    keys = streamed_tiles(pack, rng, 0.8)
    keys += keys[: len(keys) // 3]  # re-inserting a resident tile makes it most recent
    first, second = keys[: len(keys) // 2], keys[len(keys) // 2:]
    # Between the halves a frame's requests: the resident ones (hits) become most recent.
    asked = [keys[i] for i in rng.choice(len(keys), 40, replace=False)]
    for k in first:
        vt.insert(k, pack.read_tile(*k))
    missed = vt.request(asked)
    for k in second:
        vt.insert(k, pack.read_tile(*k))
    assert vt.stats()["evictions"] > 50 and 0 < len(missed) < len(asked)
    with serve_pack(vt_pack) as url:
        page = open_page(browser, f"{url}/client/vt/test/harness.html")
        page.evaluate("([slots, scene]) => vtTest.init({slots, scene})", [list(slots), pack_scene(vt_pack)])
        page.evaluate("(keys) => vtTest.insertTiles(keys)", [list(k) for k in first])
        hits = page.evaluate("(keys) => keys.map((k) => vt.cache.request(vt.geometry.tileIndex(...k)))",
                             [list(k) for k in asked])
        page.evaluate("(keys) => vtTest.insertTiles(keys)", [list(k) for k in second])
        assert {tuple(k) for k, h in zip(asked, hits) if not h} == set(missed)
        assert page.evaluate("() => vt.cache.stats.evictions") == vt.stats()["evictions"]
        tables = page.evaluate("""() => vt.geometry.paintings.map((q, p) => q.levelWidth.map((_, l) => {
            const w = q.gridWidth(l), h = q.gridHeight(l), e = [];
            for (let y = 0; y < h; ++y) for (let x = 0; x < w; ++x) e.push(vt.pageTable.lookup(p, l, x, y));
            return { w, h, e }; }))""")
        pr = probes(pack, rng, 800)
        gpu = np.asarray(page.evaluate("(p) => vtTest.sampleProbes(p)", pr.ravel().tolist()),
                         np.float32).reshape(-1, 4)
        page.close()
    cpu, _ = cpu_samples(vt, pr)
    assert np.abs(gpu[:, :3] * 255 - cpu).max() <= 2.0
    # Entry for entry (level, slot), padding included: the same LRU chose the same slots.
    for p, levels in enumerate(tables):
        for l, t in enumerate(levels):
            want = [vt.lookup((p, l, x, y)) for y in range(t["h"]) for x in range(t["w"])]
            assert [(e >> 24, e & 0xFFFFFF) for e in t["e"]] == want, (p, l)


# Two paintings on the wall z = 0 (1 mm texels), the layout both feedback passes see.
PLACEMENTS = [
    {"painting": 0, "origin": [-2.0, 1.5, 0.0], "u_axis": [1, 0, 0], "v_axis": [0, -1, 0],
     "width_m": 4.0, "height_m": 0.3},
    {"painting": 1, "origin": [2.2, 2.0, 0.0], "u_axis": [1, 0, 0], "v_axis": [0, -1, 0],
     "width_m": 1.5, "height_m": 0.9},
]
QUEST3_EYE = (2064, 2208)  # per-eye display; its feedback is 1/8: 258 x 276
POSES = [  # (camera x, y, z, target x, y, z, vertical fov), display, reduction
    ((0.0, 1.35, 1.0, 0.0, 1.35, 0.0, 90.0), QUEST3_EYE, 8),      # the long one, head on
    ((1.5, 1.5, 0.6, -0.5, 1.4, 0.0, 90.0), QUEST3_EYE, 8),       # oblique, levels 0..4
    ((-1.0, 1.4, 0.12, -1.0, 1.4, 0.0, 60.0), QUEST3_EYE, 8),     # close: level 0
    ((2.6, 1.3, 2.5, 3.0, 1.6, 0.0, 70.0), QUEST3_EYE, 8),        # the other one
    ((1.0, 1.4, 7.0, 1.0, 1.5, 0.0, 90.0), QUEST3_EYE, 8),        # both, far: levels 2, 3
    ((2.9, 1.5, 0.3, 2.9, 1.5, 0.0, 8.0), (512, 512), 1),         # a magnifier, full size
]


@functools.lru_cache(maxsize=None)
def cpu_feedback(camera, display, reduction):
    """The core's feedback pass (render_view) of the PLACEMENTS: request keys, rows top down."""
    scene = g.ExhibitionScene()
    for s, (w, h) in zip(PLACEMENTS, SIZES):
        scene.add_painting(s["painting"], g.PaintingGeometry(w, h, TILE, BORDER), s["origin"],
                           s["u_axis"], s["v_axis"], s["width_m"], s["height_m"])
    scene.commit()
    cam = g.Camera(camera[:3], camera[3:6], (0, 1, 0), camera[6], display)
    fw, fh = max(1, display[0] // reduction), max(1, display[1] // reduction)
    return g.render_view(scene, cam, fw, fh, display=False)["keys"]


def gpu_keys(result):
    """The GPU readback (flat tile indices, rows bottom up) as request keys, rows top down."""
    lut = {int(i): int(g.pack_request(*k)) for i, k in result["keys"].items()}
    lut[0xFFFFFFFF] = int(g.NO_REQUEST)
    indices = np.frombuffer(base64.b64decode(result["indices"]), "<u4")
    keys = np.array([lut[i] for i in indices.tolist()], np.uint64)
    return keys.reshape(result["height"], result["width"])[::-1]


@pytest.mark.parametrize("pose", range(len(POSES)))
def test_gpu_feedback_equals_core_feedback(vt_page, pose):
    """Per feedback pixel the GPU requests the core's tile, except where the level of detail
    lies on a level boundary (the GPU's 2 x 2 finite differences against the core's analytic
    ray differentials; sampler.glsl.js) or a tile edge falls within float32 rounding: at most
    0.5% of the pixels, each a neighbour of the core's tile in level or place."""
    page, _ = vt_page
    camera, display, reduction = POSES[pose]
    cpu = cpu_feedback(camera, display, reduction)
    view = {"view": 0, "camera": list(camera), "display": list(display), "reduction": reduction}
    (result,) = page.evaluate("([v, p]) => vtTest.feedback([v], p)", [view, PLACEMENTS])
    gpu = gpu_keys(result)
    assert gpu.shape == cpu.shape
    seen = cpu != g.NO_REQUEST
    assert seen.mean() > 0.01, "the pose must see a painting"
    differ = gpu != cpu
    assert differ.mean() <= 0.005, f"{differ.mean():.4%} of the pixels differ"
    # A differing pixel is on a boundary: levels one apart or tiles side by side, each
    # covering the other's place (or a painting's silhouette, seen by one side only).
    both = differ & (gpu != g.NO_REQUEST) & (cpu != g.NO_REQUEST)
    pg, lg, xg, yg = (a.astype(np.int64) for a in g.unpack_requests(gpu[both]))
    pc, lc, xc, yc = (a.astype(np.int64) for a in g.unpack_requests(cpu[both]))
    top = np.maximum(lg, lc)
    assert np.all(pg == pc) and np.all(np.abs(lg - lc) <= 1)
    assert np.all(np.abs((xg >> (top - lg)) - (xc >> (top - lc))) <= 1)
    assert np.all(np.abs((yg >> (top - lg)) - (yc >> (top - lc))) <= 1)


A_LECUYER = 2862933555777941757


def test_request_hash_matches_core(vt_page):
    """requests.js's slot of B = p 2^37 + l 2^32 + morton(x, y) in frame F equals
    HashProcessor.slot and the formula a (B (F + 2^20 + 1)) mod 2^64 >> (64 - bits) in Python
    integers, for random keys (27-bit paintings, 16-bit tiles) and frames up to 2^40."""
    page, _ = vt_page
    rng = np.random.default_rng(3)
    cases = [[int(rng.integers(0, 2**27 - 1)), int(rng.integers(0, 32)), int(rng.integers(0, 65536)),
              int(rng.integers(0, 65536)), int(f)] for f in rng.integers(0, 2**40, 300)]
    cases += [[0, 0, 0, 0, 0], [2**27 - 2, 31, 65535, 65535, 2**40], [3, 2, 100, 57, 7]]
    for bits in (4, 16, 28):
        got = page.evaluate("""async ([cases, bits]) => {
            const r = await import("/client/vt/requests.js");
            return cases.map(([p, l, x, y, f]) => r.hashSlot(...r.requestKey(p, l, x, y), f, bits)); }""",
                            [cases, bits])
        core = g.HashProcessor(min(bits, 20))  # 2^28 slots would take 2 GiB; slot() scales
        for (p, l, x, y, f), slot in zip(cases, got):
            key = int(g.pack_request(p, l, x, y))
            assert key == (p << 37) | (l << 32) | int(g.pack_request(0, 0, x, y))
            salt = f + 2**20 + 1
            assert slot == (A_LECUYER * (key * salt % 2**64) % 2**64) >> (64 - bits)
            assert slot >> (bits - min(bits, 20)) == core.slot(key, core.frame_salt(f))


def flat_index(pack, p, l, tx, ty):
    """The feedback's flat tile index (geometry.js): tiles of earlier paintings and levels
    first, row-major inside a level."""
    base = 0
    for q in range(p):
        geo = pack.paintings[q]
        base += sum(w * h for w, h in geo.level_tiles)
    tiles = pack.paintings[p].level_tiles
    return base + sum(w * h for w, h in tiles[:l]) + ty * tiles[l][0] + tx


@pytest.mark.parametrize("bits", [4, 6, 16])
def test_request_processing_matches_hash_processor(vt_page, vt_pack, bits):
    """One frame's feedback (the core's own, as flat indices) through requests.js gives the
    requests HashProcessor.process gives: the same keys survive the same collisions (the finer
    level, then the smaller key), whatever the order of insertion."""
    page, _ = vt_page
    pack = g.TilePack(str(vt_pack))
    cpu = np.concatenate([cpu_feedback(*POSES[k]).ravel() for k in (1, 3)])
    table = {}
    for key in set(cpu.tolist()) - {int(g.NO_REQUEST)}:
        p, l, x, y = (int(a[0]) for a in g.unpack_requests(np.array([key], np.uint64)))
        table[key] = flat_index(pack, p, l, x, y)
    flat = [table.get(int(k), 0xFFFFFFFF) for k in cpu.tolist()]
    geos = [g.PaintingGeometry(w, h, TILE, BORDER) for w, h in SIZES]
    page.evaluate("(flat) => { window.flat = new Uint32Array(flat); }", flat)
    for frame in (0, 1, 12345):
        got = page.evaluate("""async ([bits, frame]) => {
            const { RequestProcessor } = await import("/client/vt/requests.js");
            const r = new RequestProcessor(vt.geometry, vt.cache, vt.pageTable, { tableBits: bits });
            return r.process([window.flat], frame).map((i) => vt.geometry.keyOf(i)); }""",
                            [bits, frame])
        want = g.HashProcessor(bits).process([cpu], g.ResidentSet(geos), frame)["requests"]
        assert sorted(int(g.pack_request(*k)) for k in got) == sorted(want.tolist())
        assert len(want) < len(table) or bits == 16  # small tables lose some to collisions


def test_streaming_loads_what_the_core_requests(browser, vt_pack):  # noqa: F811
    """The whole runtime from a cold cache (feedback pass, asynchronous readback, hash,
    capped loading through the worker's batches, uploads within the budget): once quiet, every
    tile the core's feedback pass requests for the two eyes and the magnifier is resident,
    except tiles only level-boundary pixels asked for (test_gpu_feedback_equals_core_feedback
    bounds those), and the loads stayed within the caps."""
    views = [{"view": v, "camera": list(POSES[k][0]), "display": list(POSES[k][1]),
              "reduction": POSES[k][2]} for v, k in enumerate((1, 3, 5))]
    with serve_pack(vt_pack) as url:
        page = open_page(browser, f"{url}/client/vt/test/harness.html")
        page.evaluate("(scene) => vtTest.init({scene, slots: [20, 20], maxRequestsPerFrame: 8, "
                      "maxUploadsPerFrame: 4})", pack_scene(vt_pack))
        out = page.evaluate("([v, p]) => vtTest.stream(v, p, 400)", [views, PLACEMENTS])
        page.close()
    resident = {int(g.pack_request(*k)) for k in out["resident"]}
    wanted = set()
    for k in (1, 3, 5):
        wanted |= set(cpu_feedback(*POSES[k]).ravel().tolist())
    wanted.discard(int(g.NO_REQUEST))
    missing = wanted - resident
    assert out["frames"] < 400 and out["stats"]["failed"] == 0
    assert len(missing) <= 2, f"{len(missing)} of {len(wanted)} requested tiles not resident"
    # 8 commands a frame at most, so the cold start took at least this many frames.
    assert out["frames"] >= (len(wanted) - 12) / 8


def all_tiles(pack):
    return [(p, l, x, y) for p, q in enumerate(pack.paintings)
            for l, (nx, ny) in enumerate(q.level_tiles) for y in range(ny) for x in range(nx)]


@pytest.fixture(scope="module")
def all_resident(vt_page, vt_pack):
    """Every tile resident in the page's virtual texture and in a core VirtualTexture."""
    page, _ = vt_page
    pack = g.TilePack(str(vt_pack))
    keys = all_tiles(pack)
    page.evaluate("(keys) => vtTest.insertTiles(keys)", [list(k) for k in keys])
    vt = g.VirtualTexture(pack, slots=SLOTS)
    for k in keys:
        vt.insert(k, pack.read_tile(*k))
    return vt


@pytest.mark.parametrize("pose", [0, 1, 3])
def test_gpu_display_equals_core_sampling(vt_page, all_resident, pose):
    """The display pass's vtSample(painting, uv, vtLod(painting, uv)) at 480 x 360, every tile
    resident, against the core's trilinear sample at render_view's uv and lambda (analytic ray
    differentials) for the same pixels: PSNR >= 40 dB over the pixels both see a painting on
    (54-59 dB measured at lambda 1-4.5). They differ by the GPU's float32 uv interpolation,
    its finite-difference lambda and the 8-bit target's rounding."""
    page, _ = vt_page
    vt = all_resident
    camera, size = POSES[pose][0], (480, 360)
    view = {"view": 0, "camera": list(camera), "display": list(size)}
    rgba = base64.b64decode(page.evaluate("([v, p]) => vtTest.render(v, p)", [view, PLACEMENTS]))
    gpu = np.frombuffer(rgba, np.uint8).reshape(size[1], size[0], 4)[::-1]
    scene = g.ExhibitionScene()
    for s, (w, h) in zip(PLACEMENTS, SIZES):
        scene.add_painting(s["painting"], g.PaintingGeometry(w, h, TILE, BORDER), s["origin"],
                           s["u_axis"], s["v_axis"], s["width_m"], s["height_m"])
    scene.commit()
    cam = g.Camera(camera[:3], camera[3:6], (0, 1, 0), camera[6], size)
    r = g.render_view(scene, cam, size[0], size[1])
    painting = (r["keys"] >> np.uint64(37)).astype(np.int64)
    cpu = np.zeros((size[1], size[0], 3), np.float32)
    seen = r["keys"] != g.NO_REQUEST
    for p in range(len(SIZES)):
        m = seen & (painting == p)
        if m.any():
            cpu[m] = vt.sample(p, r["uv"][m][:, 0], r["uv"][m][:, 1], r["lod"][m], filter="trilinear")[0]
    both = seen & (gpu[..., 3] == 255)
    assert both.mean() > 0.02 and (both == seen).mean() > 0.99  # the same silhouette, but edges
    mse = np.mean((gpu[both][:, :3].astype(np.float64) - cpu[both]) ** 2)
    psnr = 10 * np.log10(255 ** 2 / max(mse, 1e-12))
    assert psnr >= 40, f"PSNR {psnr:.1f} dB"


def test_bad_pack_descriptions_are_refused(vt_page, vt_pack):
    """A scene.json pack the core would not accept (PackGeometry::validate) makes the virtual
    texture throw a clear Error before it touches WebGL; the good one is accepted."""
    page, _ = vt_page
    good = pack_scene(vt_pack)["pack"]
    p0 = good["paintings"][0]
    bad = [{**good, "border": 0}, {**good, "tile_size": 8, "border": 4},
           {**good, "table_size": [100, 8]}, {**good, "paintings": []},
           {**good, "paintings": [{**p0, "levels": p0["levels"] - 1}]},
           {**good, "paintings": [{**p0, "levels": 40}]},
           {**good, "paintings": [{**p0, "table_offset": [3, 0]}]},
           {**good, "paintings": [{**p0, "table_offset": [good["table_size"][0], 0]}]},
           {**good, "paintings": [{**p0, "index": 1}]},
           {**good, "paintings": [{**p0, "width": -5}]},
           {**good, "paintings": [{**p0, "level_tiles": [[1, 1]] * p0["levels"]}]},
           {**good, "paintings": [{**p0, "width": float("nan")}]}]
    out = page.evaluate("""async (packs) => {
        const { PackGeometry } = await import("/client/vt/geometry.js");
        return packs.map((p) => { try { new PackGeometry(p); return "accepted"; }
                                  catch (e) { return e instanceof Error ? e.message : "not an Error"; } }); }""",
                        [good] + bad)
    assert out[0] == "accepted"
    assert all(m.startswith("pack: ") for m in out[1:]), out


def test_feedback_garbage_is_ignored(vt_page):
    """Feedback pixels that name no tile (any 32-bit value past the pack's tiles, as a
    corrupted or foreign target would hold) are skipped; the valid ones among them are still
    requested, each once."""
    page, info = vt_page
    out = page.evaluate("""async (tiles) => {
        const { RequestProcessor } = await import("/client/vt/requests.js");
        const r = new RequestProcessor(vt.geometry, vt.cache, vt.pageTable, { tableBits: 16 });
        const buf = new Uint32Array(100000);
        let x = 12345;
        for (let i = 0; i < buf.length; ++i) { x = (Math.imul(x, 1103515245) + 12345) >>> 0; buf[i] = x; }
        for (let i = 0; i < buf.length; i += 1000) buf[i] = i % tiles;
        const got = r.process([buf, new Uint32Array(7)], 3);
        return { got, bad: got.filter((i) => !(i < tiles)).length };
    }""", info["tiles"])
    assert out["bad"] == 0
    assert sorted(out["got"]) == sorted({i % info["tiles"] for i in range(0, 100000, 1000)} | {0})


def test_tile_server_failures(browser, vt_pack):  # noqa: F811
    """A batch endpoint that fails: the pinned tiles' load rejects vt.ready with the server's
    answer; failing streamed tiles are counted and the frame loop keeps running on the
    resident tails."""
    scene = pack_scene(vt_pack)
    bad = {**scene, "tiles": {**scene["tiles"], "batch": "/api/tiles/0123/batch"}}
    with serve_pack(vt_pack) as url:
        page = open_page(browser, f"{url}/client/vt/test/harness.html")
        err = page.evaluate("""(scene) => vtTest.init({scene}).then(() => "resolved", (e) => String(e))""", bad)
        assert "pinned tiles failed to load" in err and "404" in err
        page.close()
        page = open_page(browser, f"{url}/client/vt/test/harness.html")
        info = page.evaluate("(scene) => vtTest.init({scene})", scene)
        page.evaluate("() => { vt.loader.url = '/api/tiles/0123/batch'; }")
        views = [{"view": 0, "camera": list(POSES[1][0]), "display": list(POSES[1][1]), "reduction": 8}]
        out = page.evaluate("([v, p]) => vtTest.stream(v, p, 40)", [views, PLACEMENTS])
        page.close()
    assert out["frames"] == 40 and out["stats"]["failed"] > 0
    assert out["stats"]["resident"] == len(out["resident"]) == info["pinned"]  # the tails only


def test_gpu_sampler_on_a_packed_gallery(browser, tmp_path):  # noqa: F811
    """Six paintings the pack's layout packer placed in a 32 x 32 merged table (offsets along
    both axes, tails of one to three levels): the GPU sampler still equals the core's."""
    rng = np.random.default_rng(2)
    sizes = [(3000, 260), (900, 900), (500, 1400), (2000, 700), (300, 300), (1200, 200)]
    images = [rng.integers(0, 256, (h, w, 3), dtype=np.uint8) for w, h in sizes]
    path = tmp_path / "gallery.pack"
    pack = g.build_pack(images, path)
    assert any(q.table_offset[1] > 0 for q in pack.paintings)
    vt = g.VirtualTexture(pack, slots=(24, 24))
    keys = streamed_tiles(pack, rng, 0.5)
    for k in keys:
        vt.insert(k, pack.read_tile(*k))
    with serve_pack(path) as url:
        page = open_page(browser, f"{url}/client/vt/test/harness.html")
        page.evaluate("(scene) => vtTest.init({scene, slots: [24, 24]})", pack_scene(path))
        page.evaluate("(keys) => vtTest.insertTiles(keys)", [list(k) for k in keys])
        pr = probes(pack, rng, 300)
        gpu = np.asarray(page.evaluate("(p) => vtTest.sampleProbes(p)", pr.ravel().tolist()),
                         np.float32).reshape(-1, 4)
        page.close()
    cpu, _ = cpu_samples(vt, pr)
    assert np.abs(gpu[:, :3] * 255 - cpu).max() <= 2.0
