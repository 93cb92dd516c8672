"""The one camera response (gigascroll.display_mapping, gallery/exposure.py): the Khronos PBR
Neutral curve against its published properties, the exposure's definitions against their
formulas, a white painting at the reference illuminance against Lambert's polygon formula, the
same pose through `render` and through a gallery frame, linear EXRs, and a walk that clips no
painting pixel."""

import math

import numpy as np
import pytest

import gigascroll as g
from gigascroll import cli
from gigascroll.display_mapping import (PAINTING_WHITE, PAPER_WHITE, Display, ExposureSetting,
                                        ev100_of_exposure, exposure_for_white,
                                        exposure_of_ev100, pbr_neutral, srgb_encode,
                                        to_srgb8)
from gigascroll.gallery import Gallery, builtin_room
from gigascroll.gallery.exposure import auto_lux, painting_lux, room_display
from gigascroll.room.builtin import LUMENS_PER_WATT, direct_irradiance

# ----------------------------------------------------------------------------- the curve


def srgb_code(linear: float) -> int:
    """IEC 61966-2-1 by hand, rounded to nearest."""
    s = 12.92 * linear if linear <= 0.0031308 else 1.055 * linear ** (1 / 2.4) - 0.055
    return int(s * 255 + 0.5)


def test_neutral_is_identity_less_the_offset_in_the_base_colour_range():
    # Khronos: c_out = c_in - 0.04 wherever 0.08 <= R, G, B <= 0.8
    rng = np.random.default_rng(1)
    c = rng.uniform(0.08, 0.8, (2000, 3))
    assert np.allclose(pbr_neutral(c), c - 0.04, atol=1e-6)
    # below 0.08 the offset is x - x^2 / 0.16 of the smallest channel
    dark = np.array([[0.02, 0.3, 0.5]])
    assert np.allclose(pbr_neutral(dark), dark - (0.02 - 0.02 ** 2 / 0.16), atol=1e-7)


def test_neutral_is_monotone_bounded_and_keeps_hue():
    grey = np.linspace(0, 50, 20001)
    out = pbr_neutral(np.repeat(grey[:, None], 3, axis=1))[:, 0]
    assert np.all(np.diff(out) >= 0) and out.max() < 1.0 and out[-1] > 0.99
    rng = np.random.default_rng(2)
    c = rng.uniform(0, 8, (5000, 3))
    o = pbr_neutral(c)
    assert o.min() >= 0 and o.max() < 1
    # no hue shift: the output lies in the plane of the input colour and the white axis
    det = np.linalg.det(np.stack([o, c, np.ones_like(c)], axis=1).astype(np.float64))
    assert np.abs(det).max() < 1e-4 * np.abs(c).max()
    # monotone in the exposure: more light never darkens any channel of any colour
    k = np.geomspace(0.01, 100, 200)
    ramp = pbr_neutral(c[None, :500] / 8 * k[:, None, None])
    assert np.diff(ramp, axis=0).min() >= -1e-6
    # the compression starts where the offset peak reaches 0.76, continuously
    knee = np.array([[0.8, 0.8, 0.8]])
    assert pbr_neutral(knee)[0, 0] == pytest.approx(0.76, abs=1e-6)
    assert pbr_neutral(knee * 1.0001)[0, 0] == pytest.approx(0.76, abs=1e-4)


def test_srgb_encode_and_the_8_bit_codes():
    for x in (0.0, 0.002, 0.0031308, 0.18, 0.5, 0.76, 1.0):
        assert int(srgb_encode(x) * 255 + 0.5) == srgb_code(x)
    assert to_srgb8(np.array([[0.0, 1.0, 0.5]]), tone="clip").tolist() == [[0, 255, 188]]
    # NaN, negative and infinite radiance: black, black and the curve's top (never past it)
    out = to_srgb8(np.array([[np.nan] * 3, [-1.0] * 3, [np.inf] * 3]))
    assert out.tolist() == [[0, 0, 0], [0, 0, 0], [255, 255, 255]]


# ----------------------------------------------------------------------------- exposure


def test_exposure_definitions():
    # EV100: L_max = 1.2 x 2^EV100 cd/m^2 (saturation-based ISO 100), luminance = 683 x radiance
    for ev in (-3.0, 0.0, 6.0, 15.0):
        radiance_at_saturation = 1.2 * 2 ** ev / 683.0
        assert exposure_of_ev100(ev) * radiance_at_saturation == pytest.approx(1.0)
        assert ev100_of_exposure(exposure_of_ev100(ev)) == pytest.approx(ev)
    # white=LUX: a white painting's radiance, albedo 0.9 x (LUX / 683) / pi, exposed to 0.8
    for lux in (50.0, 200.0, 1000.0):
        radiance = 0.9 * lux / 683.0 / math.pi
        assert exposure_for_white(lux) * radiance == pytest.approx(0.8)
    assert (PAINTING_WHITE, PAPER_WHITE, LUMENS_PER_WATT) == (g.gallery.gallery.PAINTING_REFLECTANCE,
                                                              0.8, 683.0)


@pytest.mark.parametrize("text, mode, value", [
    ("auto", "auto", None), (" AUTO ", "auto", None), ("6", "ev100", 6.0), ("-2.5", "ev100", -2.5),
    ("white=200lux", "white", 200.0), ("white=50lx", "white", 50.0), ("white=75", "white", 75.0)])
def test_exposure_option_parses(text, mode, value):
    s = ExposureSetting.parse(text)
    assert (s.mode, s.value) == (mode, value)


@pytest.mark.parametrize("text", ["", "nan", "inf", "white=", "white=0lux", "white=-5lux",
                                  "white=1e300lux", "white=nanlux", "1e9", "six", "white=200cd",
                                  "ev=6", "white=200luxx"])
def test_bad_exposure_is_a_value_error(text):
    with pytest.raises(ValueError):
        ExposureSetting.parse(text)


def test_auto_exposure_is_the_median_direct_illuminance_on_the_paintings():
    # the hall's ceiling panels are solved for 200 lux on the paintings; the scroll's spots
    # and fill for 180 + 20 at the scroll's centre
    hall = builtin_room("hall", {"a": (2000, 1500)})
    lux, how = auto_lux(hall)
    assert lux == pytest.approx(200, rel=0.02) and "median" in how
    scroll = builtin_room("scroll", {"a": (30000, 1200)})
    lux = painting_lux(scroll)
    slot = scroll.paintings[0]
    centre = (np.add(slot.origin, np.multiply(slot.u_axis, slot.width_m / 2))
              + np.multiply(slot.v_axis, slot.height_m / 2))
    normal = -np.cross(slot.u_axis, slot.v_axis)  # the room's side (z < 0)
    at_centre = direct_irradiance(scroll, centre, normal)[1] * LUMENS_PER_WATT
    assert lux.min() < at_centre < lux.max()
    assert auto_lux(scroll)[0] == pytest.approx(np.median(lux))
    assert 150 < np.median(lux) < 250
    d = room_display(scroll)
    assert d.exposure == pytest.approx(exposure_for_white(np.median(lux)))
    assert room_display(scroll, "6").exposure == pytest.approx(exposure_of_ev100(6))
    assert room_display(scroll, lighting="unlit").exposure == pytest.approx(0.8 / 0.9)


# ----------------------------------------------------------------------------- rendered


@pytest.fixture(scope="module")
def packs(tmp_path_factory):
    d = tmp_path_factory.mktemp("display")
    white = np.full((256, 1024, 3), 255, np.uint8)
    g.build_pack(white, d / "white.pack", tile_size=128, border=4)
    g.build_pack(g.render_ink_landscape(6000, 240, 0, 240), d / "ink.pack", tile_size=128, border=4)
    return d / "white.pack", d / "ink.pack"


def test_white_painting_at_the_reference_illuminance_shows_paper_white(packs):
    """Direct light only, per pixel (lighting full, many emitter samples), a white painting
    seen head on, exposed for the polygon formula's illuminance at the pixel's point: the
    pixel is exposed to 0.8, which the neutral curve shows as 0.76 (sRGB code 226) and clip as
    0.8 (code 231)."""
    pack = g.TilePack(str(packs[0]))
    room = builtin_room("scroll", pack)
    gallery = Gallery.from_room(room, pack)
    slot = room.paintings[0]
    centre = (np.add(slot.origin, np.multiply(slot.u_axis, slot.width_m / 2))
              + np.multiply(slot.v_axis, slot.height_m / 2))
    normal = -np.cross(slot.u_axis, slot.v_axis)
    lux = direct_irradiance(room, centre, normal)[1] * LUMENS_PER_WATT
    cam = gallery.camera((9, 9), fov=2.0, eye=tuple(centre + 1.0 * normal), target=tuple(centre))
    image = gallery.still(cam, lighting="full", indirect=False, light_samples=4096)
    # the 3.5 cm patch's mean: the emitter sampling's noise per pixel is about 1 %
    mid = image.reshape(-1, 3).mean(axis=0)[None]
    assert np.allclose(mid * exposure_for_white(lux), PAPER_WHITE, rtol=0.005)
    assert srgb_code(0.76) == 226 and srgb_code(0.8) == 231
    setting = ExposureSetting.parse(f"white={float(lux)!r}lux")
    for tone, code in (("neutral", 226), ("clip", 231)):
        got = room_display(room, setting, tone).srgb8(mid)
        assert np.abs(got.astype(int) - code).max() <= 1, (tone, got)


def _render(pack, tmp_path, argv, name):
    out = tmp_path / name
    rc = cli.main(["render", "--room", "scroll", "--pack", str(pack), "--width", "96",
                   "--height", "64", "--photons", "20000", "--light-samples", "32", "--spp", "1",
                   "--threads", "2", "--camera", "6,1.5,-1.6,6.4,1.45,0,50", *argv, "-o", str(out)])
    assert rc == 0
    return out


def test_render_and_a_gallery_frame_show_the_same_pixels(packs, tmp_path):
    """The pose of `render --room` as both eyes of one walk frame (same bake settings, all
    tiles resident): equal 8-bit values, at most one code apart (float order)."""
    from PIL import Image

    from gigascroll.walk.gallery_walk import GallerySource, GalleryWalk, compose_frame, walk_path

    pack = g.TilePack(str(packs[1]))
    room = builtin_room("scroll", pack)
    for argv in ([], ["--exposure", "7.5", "--tone", "clip"]):
        still = np.asarray(Image.open(_render(packs[1], tmp_path, argv, "still.png")))
        setting = ExposureSetting.parse(argv[1] if argv else "auto")
        display = room_display(room, setting, argv[3] if argv else "neutral")
        source = GallerySource(room, pack, "baked", photons=20000, bake_samples=32, threads=2,
                               response=display)
        cam = source.gallery.camera((96, 64), fov=50.0, eye=(6, 1.5, -1.6), target=(6.4, 1.45, 0))
        walk = GalleryWalk(source, pack, walk_path(room, 0.05), eye=(96, 64), magnifier=False,
                           oracle=False, wait_loads=True, threads=2)
        with g.TileLoader(pack, mode="lockfree", threads=1) as loader:
            state = walk.open_state(loader)
            for frame in range(6):
                _, (left, right, _, _) = walk.step(0, state, views=[(cam, 96, 64), (cam, 96, 64)],
                                                   moving=False)
        frame = source.response.srgb8(compose_frame(left, right))
        diff = np.abs(frame[:, :96].astype(int) - still)
        print(argv, "max", diff.max(), "share > 0", (diff > 0).mean())
        assert diff.max() <= 1 and (diff > 0).mean() < 0.01
        assert np.array_equal(frame[:, :96], frame[:, 96:])


def test_exr_stays_linear_radiance(packs, tmp_path):
    """The EXR is the still's radiance whatever --exposure and --tone say; the PNG of the same
    still is the camera response of that radiance."""
    import OpenImageIO as oiio
    from PIL import Image

    a = _render(packs[1], tmp_path, ["--exposure", "3", "--tone", "clip"], "a.exr")
    b = _render(packs[1], tmp_path, [], "b.exr")
    png = _render(packs[1], tmp_path, [], "b.png")
    ra, rb = (oiio.ImageInput.open(str(p)).read_image("float") for p in (a, b))
    assert np.array_equal(ra, rb) and ra.max() < 1.0  # a lit room's radiance: W / m^2 / sr
    pack = g.TilePack(str(packs[1]))
    room = builtin_room("scroll", pack)
    gallery = Gallery.from_room(room, pack)
    cam = gallery.camera((96, 64), fov=50.0, eye=(6, 1.5, -1.6), target=(6.4, 1.45, 0))
    from gigascroll.gallery.quality import apply_settings, light_settings
    apply_settings(gallery, light_settings(room), threads=2, photons=20000, light_samples=32)
    radiance = gallery.still(cam, spp=1)  # render --room's light: the knob's default level
    assert np.allclose(ra, radiance, rtol=1e-5, atol=1e-7)
    expected = room_display(room).srgb8(rb)
    assert np.abs(np.asarray(Image.open(png)).astype(int) - expected).max() <= 1


def test_the_default_walk_clips_no_painting_pixel(packs):
    """The demo's walk (`gigascroll gallery`: the scroll room, the default 6 s walk, the
    built-in ink landscape's colours at a lower resolution, the same shape) at the automatic
    exposure, every 30th frame's eyes and magnifier, per pixel with hits: no painting pixel
    reaches the curve's maximum (8-bit 255 in any channel), nor does any pixel of the frame;
    the brightest paper stays less than a stop above paper white, well below the exposure
    at which the neutral curve would round to 255. The clip curve at the same exposure clips
    the paper under the spots: the curve is what keeps it."""
    from gigascroll import views as v
    from gigascroll.walk.gallery_walk import walk_path
    from gigascroll.views.exhibition import Headset

    pack = g.TilePack(str(packs[1]))
    room = builtin_room("scroll", pack)
    gallery = Gallery.from_room(room, pack)
    vt = g.VirtualTexture(pack, (40, 40))
    gallery.light(vt, photons=1 << 18, threads=2)
    gallery.bake(light_samples=32, threads=2)
    display = room_display(room)
    path = walk_path(room)
    assert len(path) == 540
    headset = Headset(width=60, height=64)
    top = 1.0
    while int(srgb_encode(pbr_neutral(np.full((1, 3), top, np.float32)))[0, 0] * 255 + 0.5) < 255:
        top *= 1.05
    peak, clipped_by_clip = 0.0, 0
    for frame in range(0, len(path), 30):
        for cam, _, _ in v.frame_cameras(path, frame, headset=headset, magnifier=v.MAGNIFIER):
            gallery.stream(cam, vt)
            linear, hits = gallery.render_display(cam, vt, hits=True)
            painting = hits["slot"] >= 0
            codes = display.srgb8(linear)
            assert codes.max() < 255, frame
            peak = max(peak, float((linear[painting] * display.exposure).max(initial=0)))
            clip = Display(display.exposure, "clip").srgb8(linear)
            clipped_by_clip += int((clip[painting] == 255).any(axis=-1).sum())
    print(f"brightest painting pixel exposed to {peak:.3f}; neutral reaches 255 at {top:.2f}; "
          f"{clipped_by_clip} painting pixels clip with the clip curve")
    assert 0.8 < peak < 1.5 < top
    assert clipped_by_clip > 0


def test_the_walk_report_states_the_response(packs, tmp_path):
    """`gallery --exposure 6.5 --tone clip`: results.json and report.md say what was used, and
    the saved frame is the linear frame (--exr) through exactly that response."""
    import json

    import OpenImageIO as oiio
    from PIL import Image

    out = tmp_path / "walk"
    rc = cli.main(["gallery", str(packs[1]), "--eye", "32x32", "--seconds", "0.05",
                   "--no-video", "--no-oracle", "--photons", "20000", "--threads", "2", "--exr",
                   "--exposure", "6.5", "--tone", "clip", "--out", str(out)])
    assert rc == 0
    results = json.loads((out / "results.json").read_text())
    d = results["display"]
    assert d["tone"] == "clip" and d["ev100"] == pytest.approx(6.5)
    assert d["exposure"] == pytest.approx(683 / (1.2 * 2 ** 6.5))
    assert results["settings"]["tone"] == "clip" and "EV100 6.50" in (out / "report.md").read_text()
    name = results["saved_frames"][-1]
    linear = oiio.ImageInput.open(str(out / "frames" / f"{name}.exr")).read_image("float")
    png = np.asarray(Image.open(out / "frames" / f"{name}.png"))
    assert np.array_equal(png, to_srgb8(linear, d["exposure"], "clip"))
