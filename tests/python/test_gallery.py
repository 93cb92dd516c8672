"""The Gallery: one scene for feedback, display and light (issue 13). References: analytic ray
geometry in numpy, the ExhibitionScene's feedback pass, the sRGB formula, brute-force irradiance."""

import math

import numpy as np
import pytest

import gigascroll as g
from gigascroll.gallery import PAINTING_REFLECTANCE, Gallery, PaintingSlot, RoomSpec, Surface, painting_albedo

from gallery_checks import box_room, example_room_files, quad, uniform_pack

RED = (230, 30, 20)


@pytest.fixture(scope="module")
def red_pack(tmp_path_factory):
    return uniform_pack(tmp_path_factory.mktemp("gal") / "p.pack", {"white": (250, 250, 250), "red": RED})


@pytest.fixture(scope="module")
def lit(red_pack):
    gal = Gallery.from_room(box_room(), red_pack)
    vt = g.VirtualTexture(red_pack)
    gal.light(vt, photons=100_000)
    gal.bake(spacing=0.2, light_samples=16, progress=True)
    done, rows = gal._bake_progress()
    assert done == rows > 0  # every lattice row counted once
    return gal, vt


def srgb_linear(c):
    c = np.asarray(c) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def test_slots_bind_by_name_and_index(red_pack):
    by_name = Gallery.from_room(box_room(painting="red"), red_pack)
    by_index = Gallery.from_room(box_room(painting=1), red_pack)
    assert by_name.slot_paintings == by_index.slot_paintings == [1]
    assert by_name.painting_count == 1 and by_name.emitter_count == 2
    # 7 quads of the room and the painting rectangle
    assert by_name.triangle_count == 16


@pytest.mark.parametrize("change, message", [
    (lambda s: s.paintings[0].__setattr__("painting", "missing"), "not in the pack"),
    (lambda s: s.paintings[0].__setattr__("painting", 7), "not in the pack"),
    (lambda s: s.surfaces.pop(), "no light"),
    (lambda s: s.surfaces[0].__setattr__("albedo", (1.0, 0.5, 0.5)), r"\[0, 1\)"),
    (lambda s: s.surfaces[0].__setattr__("albedo", (math.nan, 0.5, 0.5)), "not finite"),
    (lambda s: s.surfaces[0].vertices.__setitem__((0, 0), math.nan), "not finite"),
    (lambda s: s.paintings[0].__setattr__("origin", (0, math.nan, 0)), "not finite"),
    (lambda s: s.paintings[0].__setattr__("u_axis", (1, 1, 0)), "orthonormal"),
    (lambda s: s.paintings[0].__setattr__("width_m", -1.0), "positive"),
    (lambda s: s.surfaces[0].__setattr__("triangles", np.array([[0, 1, 9]])), "outside"),
])
def test_bad_rooms_are_refused_clearly(red_pack, change, message):
    spec = box_room()
    change(spec)
    with pytest.raises(ValueError, match=message):
        Gallery.from_room(spec, red_pack)


def test_from_room_takes_a_path(red_pack):
    gal = Gallery.from_room(box_room(), red_pack.path)
    assert gal.painting_count == 1


def test_unlit_display_is_the_albedo_and_hits_match_ray_geometry(red_pack):
    gal = Gallery.from_room(box_room(), red_pack)
    vt = g.VirtualTexture(red_pack)
    cam = gal.camera((40, 30), fov=70)
    rgb, hits = gal.render_display(cam, vt, lighting="unlit", hits=True)
    # The painting plane z = -1.999 seen through each pixel centre, in numpy.
    eye = np.array(cam.position)
    on = hits["slot"] == 0
    assert 50 < on.sum() < 40 * 30
    for y, x in zip(*np.nonzero(on)):
        d = np.array(cam.direction(x + 0.5, y + 0.5))
        t = (-1.999 - eye[2]) / d[2]
        p = eye + t * d
        assert np.allclose(hits["position"][y, x], p, atol=1e-4)
        assert hits["uv"][y, x] == pytest.approx([(p[0] + 1) / 2, 2.0 - p[1]], abs=1e-6)
    expected = PAINTING_REFLECTANCE * srgb_linear(RED)
    assert np.allclose(rgb[on], expected, rtol=1e-2)
    assert np.allclose(painting_albedo(np.array(RED, np.uint8)), expected, rtol=1e-6)
    # Room surfaces show their albedo (walls 0.6, floor 0.8); the light its albedo 0 plus emission 5.
    off = ~on & (hits["slot"] == -1)
    values = rgb[off][:, 0].astype(float)
    assert np.all(np.min(np.abs(values[:, None] - np.array([0.6, 0.8, 5.0])[None]), axis=1) < 1e-6)
    assert not np.isnan(hits["lod"][on]).any() and np.isnan(hits["lod"][~on]).all()


def test_feedback_on_the_gallery_matches_the_exhibition_scene(red_pack):
    """The feedback pass over the gallery's one BVH asks for the tiles the ExhibitionScene
    (the views' own scene, an independent BVH of the same painting) asks for."""
    gal = Gallery.from_room(box_room(gap=0.5), red_pack)
    cam = g.Camera([0.3, 1.6, 1.0], [-0.2, 1.4, -2], [0, 1, 0], 60, resolution=(96, 64))
    ex = g.ExhibitionScene()
    p = red_pack.paintings[1]
    ex.add_painting(1, g.PaintingGeometry(p.width, p.height, red_pack.tile_size, red_pack.border),
                    [-1.0, 2.0, -1.5], [1, 0, 0], [0, -1, 0], 2.0, 1.0)
    ex.commit()
    ours = gal.render_view(cam, width=96, height=64)
    theirs = g.render_view(ex, cam, 96, 64)
    seen = ours["keys"] != g.NO_REQUEST
    assert seen.sum() > 500
    assert np.array_equal(ours["keys"][seen], theirs["keys"][seen])
    assert np.allclose(ours["lod"][seen], theirs["lod"][seen])
    assert np.allclose(ours["uv"][seen], theirs["uv"][seen])
    # The room's walls hide nothing here: every painting pixel of the exhibition is seen.
    assert np.array_equal(seen, theirs["keys"] != g.NO_REQUEST)


def test_display_level_follows_the_feedback_lambda(lit):
    gal, vt = lit
    cam = gal.camera((48, 32), fov=60)
    _, hits = gal.render_display(cam, vt, lighting="full", hits=True)
    fb = gal.render_view(cam, width=48, height=32)
    on = hits["slot"] == 0
    assert np.allclose(hits["lod"][on], fb["lod"][on], atol=1e-3)
    assert np.allclose(hits["uv"][on], fb["uv"][on], atol=1e-6)
    # radiance = albedo x E / pi (+ emission, none on the painting): E reproduces the pixel.
    rgb, hits = gal.render_display(cam, vt, lighting="baked", hits=True)
    albedo = painting_albedo(np.array(RED, np.uint8))
    assert np.allclose(rgb[on], albedo * hits["irradiance"][on] / math.pi, rtol=2e-2)


def direct_irradiance_brute(p, n, light_c=(0, 2.999, 0), half=0.5, radiance=5.0, m=200):
    """Unoccluded irradiance from the square ceiling light at point p (normal n), midpoint rule."""
    xs = (np.arange(m) + 0.5) / m * 2 * half - half
    X, Z = np.meshgrid(xs + light_c[0], xs + light_c[2])
    L = np.stack([X, np.full_like(X, light_c[1]), Z], -1) - p
    d2 = (L ** 2).sum(-1)
    cos_x = np.clip(L @ n, 0, None) / np.sqrt(d2)
    cos_l = np.clip(L[..., 1], 0, None) / np.sqrt(d2)  # light faces -y: cos = (p - l) . (-y) / d
    return radiance * (cos_x * cos_l / d2).sum() * (2 * half / m) ** 2


def test_full_lighting_direct_part_matches_quadrature(red_pack):
    """Without indirect light (black walls), full lighting of the floor below the light is the
    quadrature of the light's irradiance times albedo / pi."""
    spec = box_room(wall=(0.0, 0.0, 0.0), floor=(0.5, 0.5, 0.5))
    spec.paintings = []
    gal = Gallery.from_room(spec, red_pack)
    vt = g.VirtualTexture(red_pack)
    gal.light(vt, photons=20_000, light_samples=256)
    cam = g.Camera([0, 2.0, 0.01], [0, 0, 0], [0, 0, -1], 20, resolution=(9, 9))
    rgb, hits = gal.render_display(cam, vt, lighting="full", hits=True)
    for y, x in [(4, 4), (1, 1), (7, 2)]:
        p = hits["position"][y, x].astype(float)
        E = direct_irradiance_brute(p, np.array([0, 1.0, 0]))
        # The floor's photons (after one floor bounce nothing else reflects) add no gathers:
        # photons are stored only after a first bounce, and they land on black walls.
        assert rgb[y, x, 0] == pytest.approx(0.5 * E / math.pi, rel=0.05)


def test_baked_matches_full_and_modes_are_finite(lit):
    gal, vt = lit
    cam = gal.camera((48, 36), fov=70)
    full = gal.render_display(cam, vt, lighting="full")
    baked = gal.render_display(cam, vt, lighting="baked")
    assert np.isfinite(full).all() and np.isfinite(baked).all()
    rel = np.abs(baked - full).mean() / full.mean()
    assert rel < 0.15
    out = np.zeros_like(full)
    assert gal.render_display(cam, vt, lighting="baked", out=out) is out
    assert np.array_equal(out, baked)


def test_bad_render_arguments(lit):
    gal, vt = lit
    cam = gal.camera((8, 8))
    with pytest.raises(ValueError, match="lighting"):
        gal.render_display(cam, vt, lighting="sunny")
    with pytest.raises(ValueError, match="out must"):
        gal.render_display(cam, vt, out=np.zeros((8, 8, 3), np.float64))
    with pytest.raises(ValueError, match="spacing"):
        gal.bake(spacing=math.nan)
    with pytest.raises(ValueError, match="radius"):
        gal.light(vt, radius=-1.0)
    with pytest.raises(ValueError, match="spacing too fine"):
        gal.bake(spacing=1e-5)
    with pytest.raises(ValueError, match="spacing too fine"):  # from the worker thread too
        gal.bake(spacing=1e-5, progress=True)


def test_render_cli_renders_a_room_still(tmp_path, red_pack, gigascroll_cli):
    import OpenImageIO as oiio

    out = tmp_path / "still.exr"
    r = gigascroll_cli("render", "--room", "scroll", "--pack", red_pack.path, "--width", 48, "--height", 32,
                       "--photons", 20000, "--lighting", "full", "-o", out)
    assert r.returncode == 0, r.stderr
    assert "lighting full" in r.stdout and out.exists()
    img = oiio.ImageBuf(str(out))
    pixels = np.asarray(img.get_pixels(oiio.FLOAT))
    assert pixels.shape == (32, 48, 3) and np.isfinite(pixels).all() and pixels.max() > 0


def test_python_render_accepts_a_gallery(red_pack):
    gal = Gallery.from_room(box_room(), red_pack)
    cam = gal.camera((24, 16))
    image, stats = g.render(gal, cam, photons=20000, lighting="baked", return_stats=True)
    assert image.shape == (16, 24, 3) and np.isfinite(image).all()
    assert stats["bake_points"] > 0 and gal.baked


@pytest.mark.parametrize("args, message", [
    (["--room", "scroll"], "needs --pack"),
    (["--room", "nowhere.glb", "--pack", "PACK"], "no such room file"),
    (["--room", "scroll", "--pack", "PACK", "--camera", "1,2,3"], "6 or 7"),
    (["--room", "scroll", "--pack", "PACK", "--camera", "0,0,0,0,0,0"], "must differ"),
    (["--room", "scroll", "--pack", "missing.pack"], "cannot open pack"),
    (["cornell", "--room", "scroll", "--pack", "PACK"], "not both"),
])
def test_render_cli_bad_room_input(tmp_path, red_pack, gigascroll_cli, args, message):
    args = [str(red_pack.path) if a == "PACK" else a for a in args]
    r = gigascroll_cli("render", *args, "-o", tmp_path / "x.png", cwd=tmp_path)
    assert r.returncode == 2 and message in r.stderr, r.stderr
    assert not (tmp_path / "x.png").exists()


def test_stream_makes_the_views_tiles_resident(tmp_path):
    """Close to a fine painting the view asks for level-0 tiles that are not pinned; stream()
    inserts exactly the missing ones and their missing parents (the coarser level trilinear
    filtering reads), after which the feedback's requests and their parents all hit."""
    from gigascroll.gallery.tile_keys import parent_keys
    from gallery_checks import gradient_pack

    pack = gradient_pack(tmp_path / "g.pack", size=(1024, 512))
    gal = Gallery.from_room(box_room(painting="gradient"), pack)
    vt = g.VirtualTexture(pack, (24, 24))
    cam = g.Camera([0, 1.5, -1.5], [0, 1.5, -2], [0, 1, 0], 50, resolution=(96, 64))
    keys = gal.render_view(cam, width=96, height=64)["keys"]
    wanted = np.unique(keys[keys != g.NO_REQUEST])
    wanted = np.union1d(wanted, parent_keys(wanted, np.array([p.levels for p in pack.paintings])))
    before = vt.stats()["resident"]
    missing = len(vt.request(wanted))
    assert missing > 0
    assert gal.stream(cam, vt) == missing
    assert vt.stats()["resident"] == before + missing
    assert len(vt.request(wanted)) == 0


def test_render_cli_renders_the_example_room_file(tmp_path, gigascroll_cli):
    room = example_room_files(tmp_path) / "room.glb"
    out = tmp_path / "still.png"
    r = gigascroll_cli("render", "--room", room, "--pack", tmp_path / "ex.pack", "--width", 40, "--height", 30,
                       "--photons", 20000, "--lighting", "unlit", "-o", out)
    assert r.returncode == 0, r.stderr
    assert "2 paintings" in r.stdout and out.exists()


def test_relighting_reuses_nothing_stale_a_fresh_gallery_would_not_read(tmp_path):
    """light() takes the previous lighting's painting albedo when it reads the same level of the
    same pack: a gallery relit at radii that move the level (a scroll-like strip, whose pinned
    tail starts wide, read coarser for wide gathers) and back renders bit for bit what a fresh
    gallery lit once renders, and another pack of the same shape (other texels) is read anew."""
    import dataclasses

    from gallery_checks import gradient_pack

    size = (4096, 32)
    packs = [gradient_pack(tmp_path / "a.pack", size=size, tile_size=16),
             uniform_pack(tmp_path / "b.pack", {"gradient": (40, 200, 90)}, size=size, tile_size=16)]
    room = box_room(painting="gradient", floor=(0.9, 0.9, 0.9))
    width_m = 3.6
    room = dataclasses.replace(room, surfaces=[s for s in room.surfaces], paintings=[PaintingSlot(
        "gradient", origin=(-1.8, 1.0, -1.999), u_axis=(1, 0, 0), v_axis=(0, -1, 0), width_m=width_m,
        height_m=width_m * size[1] / size[0], name="main")])
    relit = Gallery.from_room(room, packs[0])
    cam = relit.camera((24, 18), fov=70)
    levels = set()
    for pack, radius in [(0, 0.001), (0, 1.0), (0, 0.001), (0, None), (1, None), (0, None)]:
        vt = g.VirtualTexture(packs[pack])
        if pack == 1:
            relit = Gallery.from_room(room, packs[0])  # lit once from pack a, then given b's texture
            relit.light(g.VirtualTexture(packs[0]), photons=20_000)
        st = relit.light(vt, photons=20_000, radius=radius)
        levels.add(tuple(st["albedo_levels"]))
        relit.bake(spacing=0.5, light_samples=2)
        fresh = Gallery.from_room(room, packs[pack])
        fresh.light(vt, photons=20_000, radius=radius)
        fresh.bake(spacing=0.5, light_samples=2)
        assert np.array_equal(relit.render_display(cam, vt, lighting="baked"),
                              fresh.render_display(cam, vt, lighting="baked"))
    assert len(levels) > 1  # the radii did move the level read


def test_a_texture_of_another_pack_is_refused_clearly(lit, tmp_path):
    """light() and render_display() check the texture against the gallery's paintings: a pack
    with fewer paintings, or a painting of another size, is a ValueError naming the painting."""
    gal, vt = lit
    cam = gal.camera((8, 8))
    one = g.VirtualTexture(uniform_pack(tmp_path / "one.pack", {"white": (250, 250, 250)}))
    other_size = g.VirtualTexture(uniform_pack(tmp_path / "size.pack", {"white": (250, 250, 250), "red": RED},
                                               size=(128, 128)))
    for wrong, message in ((one, "painting 1 is not in the virtual texture's pack"),
                           (other_size, "painting 1 is not the one the gallery was built from")):
        with pytest.raises(ValueError, match=message):
            gal.render_display(cam, wrong, lighting="baked")
        with pytest.raises(ValueError, match=message):
            gal.light(wrong, photons=1000)
    assert gal.render_display(cam, vt, lighting="baked").shape == (8, 8, 3)  # still lit and baked

def test_relighting_at_other_photon_counts_renders_what_a_fresh_gallery_renders(tmp_path):
    """light() traces into the previous lighting's photon list and builds its map on the previous
    map's storage: relit at more, fewer and again more photons (sphere and disc gathers), the
    gallery renders bit for bit what a fresh gallery lit once renders."""
    from gallery_checks import gradient_pack

    pack = gradient_pack(tmp_path / "a.pack")
    room = box_room(painting="gradient", floor=(0.9, 0.9, 0.9))
    relit = Gallery.from_room(room, pack)
    vt = g.VirtualTexture(pack)
    cam = relit.camera((24, 18), fov=70)
    for photons, disc in [(40_000, False), (5_000, True), (60_000, True), (20_000, False)]:
        st = relit.light(vt, photons=photons, disc=disc)
        relit.bake(spacing=0.5, light_samples=2)
        fresh = Gallery.from_room(room, pack)
        st_fresh = fresh.light(vt, photons=photons, disc=disc)
        fresh.bake(spacing=0.5, light_samples=2)
        assert st["photons_stored"] == st_fresh["photons_stored"] > 0
        assert np.array_equal(relit.render_display(cam, vt, lighting="baked"),
                              fresh.render_display(cam, vt, lighting="baked"))
