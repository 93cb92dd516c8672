"""The mottle measure (gallery.mottle) on synthetic fields of known mottle, its surface classes
on a built room, and the baked light beside a painting lying on the floor against Mitsuba 3
(the band of one lattice cell that covered lattice points spread, gone with fill_covered)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import gigascroll as g
from gigascroll.gallery import Gallery, PaintingSlot
from gigascroll.gallery.mottle import (gaussian_blur, masked_blur, mottle, noise_gain, pool_segments,
                                       surface_segments)

from gallery_checks import box_room, uniform_pack
from test_gallery_mitsuba import mitsuba_still

H, W = 96, 160


def sinusoids(amplitudes, wavelengths, seed=0):
    """A sum of plane waves of the given amplitudes and wavelengths (pixels), random
    directions and phases, and the RMS each keeps after a Gaussian blur of sigma 2 px
    (the Fourier transform of a Gaussian: exp(-2 pi^2 sigma^2 / lambda^2))."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:H, 0:W].astype(np.float64)
    field = np.zeros((H, W))
    kept = []
    for a, lam in zip(amplitudes, wavelengths):
        th, ph = rng.uniform(0, 2 * math.pi, 2)
        field += a * np.sin(2 * math.pi * (x * math.cos(th) + y * math.sin(th)) / lam + ph)
        kept.append(a * math.exp(-2 * math.pi ** 2 * 2.0 ** 2 / lam ** 2))
    return field, kept


def test_blur_and_masked_blur_against_brute_force():
    rng = np.random.default_rng(1)
    a = rng.random((20, 24))
    m = rng.random((20, 24)) > 0.3
    k = np.exp(-0.5 * (np.arange(-6, 7) / 2.0) ** 2)
    k /= k.sum()
    yy, xx = np.mgrid[0:20, 0:24]
    brute = np.zeros_like(a)
    num, den = np.zeros_like(a), np.zeros_like(a)
    for dy in range(-6, 7):
        for dx in range(-6, 7):
            ys, xs = yy + dy, xx + dx
            ok = (ys >= 0) & (ys < 20) & (xs >= 0) & (xs < 24)
            w = k[dy + 6] * k[dx + 6]
            vals = np.where(ok, a[ys.clip(0, 19), xs.clip(0, 23)], 0)
            inside = np.where(ok, m[ys.clip(0, 19), xs.clip(0, 23)], False)
            brute += w * vals
            num += w * vals * inside
            den += w * inside
    assert np.allclose(gaussian_blur(a, 2.0), brute)
    got = masked_blur(a, m, 2.0)
    assert np.allclose(got[m], (num / den)[m]) and np.isnan(got[~m]).all()
    assert noise_gain(2.0) == pytest.approx(np.sqrt(((k[:, None] * k[None, :]) ** 2).sum()))


def test_known_mottle_comes_back_and_pixel_noise_goes():
    """Ours = reference x (1 + mottle): plane waves of 3% and 2% at 40-90 px wavelengths
    (RMS sqrt(sum a^2 / 2) after the blur's analytic attenuation). The reference carries 4%
    white pixel noise (Mitsuba's), which the 2 px blur takes to 4% x noise_gain. A second
    segment, with no mottle, beside the first: its figure stays at the noise alone, so the
    blur does not carry one segment's error into the next."""
    y, x = np.mgrid[0:H, 0:W].astype(np.float64)
    smooth = 1.0 + 0.5 * x / W + 0.3 * np.cos(y / H * 2)
    field, kept = sinusoids([0.03, 0.02], [90.0, 40.0])
    segments = np.where(x < W / 2, 0, 1)
    classes = {0: "walls", 1: "paintings"}
    rng = np.random.default_rng(7)
    noise = 0.04
    ref = smooth * (1 + noise * rng.standard_normal((H, W)))
    ours = smooth * np.where(segments == 0, 1 + field, 1.0)
    as_rgb = lambda a: np.repeat(a[..., None], 3, axis=2)
    m = mottle(as_rgb(ours), as_rgb(ref), segments, classes, sigma=2.0)
    # the mottle measured on the left segment only: its own RMS there, not the global one
    left = segments == 0
    field_left = masked_blur(field, left, 2.0)[left]
    expected_walls = math.hypot(float(np.sqrt(np.mean(field_left ** 2))), noise * noise_gain(2.0))
    assert m["walls"]["rms"] == pytest.approx(expected_walls, rel=0.15)
    # and about the analytic figure (the half image holds a few wavelengths only)
    assert m["walls"]["rms"] == pytest.approx(math.sqrt(sum(a * a / 2 for a in kept)), rel=0.35)
    # the right segment: noise only
    assert m["paintings"]["rms"] == pytest.approx(noise * noise_gain(2.0), rel=0.3)
    assert m["paintings"]["rms"] < 0.25 * m["walls"]["rms"]
    # the reference's own noise after the blur, estimated from its pixel residual
    assert m["paintings"]["reference_noise"] == pytest.approx(noise * noise_gain(2.0), rel=0.25)
    assert m["floor"] is None


def test_pool_segments_keeps_pure_pixels_only():
    s = np.zeros((6, 6), np.int64)
    s[:, 4:] = 1
    s[0, 0] = 2
    assert pool_segments(s, 3, margin=0).tolist() == [[-1, -1], [0, -1]]
    # with the default margin a pixel also needs its 8 neighbours (inside the image) to agree
    assert pool_segments(s, 3).tolist() == [[-1, -1], [-1, -1]]
    big = np.zeros((30, 30), np.int64)
    big[:, 18:] = 1
    pooled = pool_segments(big, 3)
    # brute force: pixel (y, x) kept where every pixel of its 3 x 3 neighbourhood inside the
    # 10 x 10 image lies wholly on one segment
    expect = np.full((10, 10), -1)
    for y in range(10):
        for x in range(10):
            cols = range(3 * max(0, x - 1), 3 * min(10, x + 2))
            segs = {int(big[0, c]) for c in cols}
            if len(segs) == 1:
                expect[y, x] = segs.pop()
    assert pooled.tolist() == expect.tolist()


@pytest.fixture(scope="module")
def floor_room(tmp_path_factory):
    """box_room with its painting lying on the floor, 1 mm above it, under the light."""
    pack = uniform_pack(tmp_path_factory.mktemp("mottle") / "p.pack", {"grey": (200, 200, 200)})
    room = box_room(painting="grey")
    room.paintings = [PaintingSlot("grey", origin=(-0.5, 0.001, -0.5), u_axis=(1, 0, 0), v_axis=(0, 0, 1),
                                   width_m=1.0, height_m=0.5, name="main")]
    gal = Gallery.from_room(room, pack)
    return gal, g.VirtualTexture(pack)


def test_surface_classes_follow_the_geometry(floor_room):
    gal, vt = floor_room
    cam = g.Camera([0, 1.5, 1.8], [0, 1.0, -2], [0, 1, 0], 80, resolution=(64, 48))
    _, hits = gal.render_display(cam, vt, lighting="unlit", hits=True)
    seg, classes = surface_segments(gal.spec, hits["position"], hits["slot"])
    p = hits["position"]
    cls = np.array([classes.get(int(s), "none") for s in seg.ravel()]).reshape(seg.shape)
    # brute force: by coordinates (box_room: floor y = 0, ceiling y = 3, walls at |x| or |z| = 2)
    on_painting = hits["slot"] == 0
    assert (cls[on_painting] == "paintings").all() and on_painting.sum() > 50
    found = np.isfinite(p[..., 0]) & ~on_painting
    expect = np.where(np.abs(p[..., 1]) < 1e-4, "floor", np.where(np.abs(p[..., 1] - 3) < 1e-4, "ceiling", "walls"))
    light = (np.abs(p[..., 1] - 2.999) < 1e-4) & (np.abs(p[..., 0]) < 0.5) & (np.abs(p[..., 2]) < 0.5)
    expect = np.where(light, "other", expect)
    assert (cls[found] == expect[found]).mean() > 0.99
    assert {"floor", "walls", "ceiling"} <= set(cls[found].tolist())


@pytest.fixture(scope="module")
def hall_table(tmp_path_factory):
    """The hall with two flat grey paintings of 0.5 m x 0.25 m lying on its table."""
    from gigascroll.room.builtin import hall_room

    pack = uniform_pack(tmp_path_factory.mktemp("hall") / "p.pack", {"a": (200, 200, 200), "b": (180, 180, 180)})
    gal = Gallery.from_room(hall_room(pack, texel_m=0.002), pack)
    return gal, g.VirtualTexture(pack)


def test_table_beside_the_paintings_lying_on_it_is_not_darkened(hall_table):
    """The hall's baked light on the table top within one lattice cell of the paintings lying
    1 mm above it, against Mitsuba: the lattice points under a painting are covered and filled
    from their lit neighbours (bake(fill_covered=True), the default), so the cells straddling
    a painting's edge are no darker than Mitsuba's table there; without the fill they are (the
    stair-stepped band)."""
    gal, vt = hall_table
    W, H, SS = 48, 36, 3
    s = gal.spec.paintings[1]
    corner = np.array(s.origin) + 0.8 * s.width_m * np.array(s.u_axis) + s.height_m * np.array(s.v_axis)
    eye, target = (corner + [0.0, 0.5, 0.4]).tolist(), corner.tolist()
    cam = g.Camera(eye, target, [0, 1, 0], 45, resolution=(W * SS, H * SS))
    ref = mitsuba_still(gal, g.Camera(eye, target, [0, 1, 0], 45, resolution=(W, H)), "hall_table")
    gal.light(vt, photons=1 << 19)
    top = 0.70  # rooms.TABLE_HEIGHT
    ratios = {}
    for fill in (True, False):
        st = gal.bake(fill_covered=fill)
        img, hits = gal.render_display(cam, vt, lighting="baked", hits=True)
        img = img.reshape(H, SS, W, SS, 3).mean(axis=(1, 3))
        p = hits["position"].reshape(H, SS, W, SS, 3)
        # table-top pixels all of whose samples lie outside the paintings, within one
        # lattice spacing of one
        d = np.full(p.shape[:-1], np.inf)
        for slot in gal.spec.paintings:
            x0, z0 = slot.origin[0], slot.origin[2]
            dx = np.maximum(np.maximum(x0 - p[..., 0], p[..., 0] - x0 - slot.width_m), 0)
            dz = np.maximum(np.maximum(z0 - p[..., 2], p[..., 2] - z0 - slot.height_m), 0)
            d = np.minimum(d, np.hypot(dx, dz))
        on_top = (np.abs(p[..., 1] - top) < 1e-4) & (d > 0.002) & (d < st["spacing"])
        band = on_top.all(axis=(1, 3))
        assert band.sum() > 30
        ratios[fill] = float(img[band].sum() / ref[band].sum())
        if fill:
            assert st["bake_points_covered"] > 0

    assert abs(ratios[True] - 1) < 0.04, ratios
    assert ratios[False] < ratios[True] - 0.05, ratios


@pytest.mark.parametrize("options", [{"indirect_filter": -1.0}, {"indirect_filter": float("nan")},
                                     {"indirect_filter": 17.0}, {"indirect_filter": True},
                                     {"indirect_filter": "1"}, {"fill_covered": "yes"}, {"fill_covered": 1},
                                     {"final_gather": -1}, {"final_gather": 4097}, {"final_gather": 2.0},
                                     {"final_gather": True}])
def test_bake_refuses_bad_fill_and_filter_options(floor_room, options):
    gal, vt = floor_room
    if not gal.lit:
        gal.light(vt, photons=10_000)
    with pytest.raises(ValueError):
        gal.bake(spacing=0.5, **options)


@pytest.mark.parametrize("smoothing", [{"indirect_filter": 2.0, "final_gather": 0}, {"final_gather": 16}])
def test_filter_and_final_gather_smooth_the_light_on_a_flat_floor(floor_room, smoothing):
    """bake(indirect_filter=2) and bake(final_gather=16) (the default): the baked light on the
    floor, far from the walls and the painting, deviates less from its own smooth (quadratic)
    fit, in 10 cm squares, than the photon density estimate at each point (both off); the
    direct part is
    untouched (indirect=False: the same bake either way)."""
    gal, vt = floor_room
    cam = g.Camera([0, 2.5, 1.2], [0, 0, 1.2], [0, 0, -1], 40, resolution=(64, 64))
    gal.light(vt, photons=50_000)

    def deviation(**options):
        gal.bake(spacing=0.05, **options)
        _, hits = gal.render_display(cam, vt, lighting="baked", hits=True)
        p, e = hits["position"].reshape(-1, 3), hits["irradiance"][..., 1].ravel()
        keep = (np.abs(p[:, 1]) < 1e-4) & (np.abs(p[:, 0]) < 1.4) & (np.abs(p[:, 2] - 1.2) < 0.5)
        x, z, e = p[keep, 0], p[keep, 2] - 1.2, e[keep]
        basis = np.stack([np.ones_like(x), x, z, x * x, x * z, z * z], 1)
        fit = basis @ np.linalg.lstsq(basis, e, rcond=None)[0]
        # the residual's mean per 10 cm square of floor: mottle at the scale the eye sees,
        # not the final gather's per-point noise at the lattice's 5 cm
        cells = np.floor(x / 0.1).astype(int) * 1000 + np.floor(z / 0.1).astype(int)
        _, inverse, counts = np.unique(cells, return_inverse=True, return_counts=True)
        means = np.bincount(inverse, weights=e / fit - 1) / counts
        return float(np.sqrt(np.mean(means[counts >= 4] ** 2))), e

    raw, _ = deviation(indirect_filter=0.0, final_gather=0)
    smooth, _ = deviation(**smoothing)
    assert smooth < 0.6 * raw, (raw, smooth)
    gal.light(vt, photons=50_000, indirect=False)
    _, direct_raw = deviation(indirect_filter=0.0, final_gather=0)
    _, direct_filtered = deviation(**smoothing)
    assert np.array_equal(direct_raw, direct_filtered)


def test_bench_mottle_writes_figures_and_refuses_bad_options(tmp_path):
    """A tiny run of `gigascroll bench mottle` (one room, 4 spp reference): results.json with
    each class's figures and the plot; bad options exit with 2."""
    pytest.importorskip("mitsuba")
    import json

    from gigascroll.cli import main

    out = tmp_path / "out"
    base = ["bench", "mottle", "--rooms", "example", "--width", "24", "--height", "14", "--supersample", "2",
            "--reference-spp", "4", "--timing-spp", "1", "--photons", "12", "--spacings", "25",
            "--bake-samples", "1", "--reference-cache", str(tmp_path / "cache"), "--out", str(out)]
    assert main(base) == 0
    r = json.loads((out / "results.json").read_text())
    c = r["rooms"]["example"]["configs"][0]
    assert c["photons_log2"] == 12 and c["mottle"]["walls"]["rms"] > 0 and c["mottle"]["walls"]["pixels"] > 0
    assert (out / "error_vs_bake.png").stat().st_size > 0
    # the knob's level instead of the grid, re-timed in alternated rounds
    assert main(base + ["--quality", "draft", "--timing-rounds", "2"]) == 0
    c = json.loads((out / "results.json").read_text())["rooms"]["example"]["configs"][0]
    from gigascroll.benchmarks.mottle import room_and_pack
    from gigascroll.gallery.quality import light_settings

    knob = light_settings(room_and_pack("example", tmp_path / "room")[0], quality="draft")
    assert c["quality"] == "draft" and 1 << c["photons_log2"] == knob.photons
    assert c["final_gather"] == knob.final_gather and c["sparse"] == knob.sparse_final_gather
    assert len(c["light_and_bake_rounds"]) == 2 and c["light_and_bake_over_first"] == 1.0
    for bad in (["--rooms", "attic"], ["--sparse", "2"], ["--quality", "best"], ["--timing-rounds", "-1"], ["--sigma", "0"], ["--sigma", "nan"], ["--photons", "40"],
                ["--indirect-filters", "x"], ["--indirect-filters", "-1"], ["--disc", "2"],
                ["--gather-strides", "3"], ["--radius-factors", "0"], ["--radius-factors", "x"],
                ["--radius-factors", "nan"], ["--fill-covered", "yes"], ["--width", "0"]):
        with pytest.raises(SystemExit) as e:
            raise SystemExit(main(base + bad))
        assert e.value.code == 2, bad
