"""Fixed foveation of the gallery walk (gigascroll.walk.foveation): the fovea's crop camera
traces the eye's own rays, so the foveated frame equals the unfoveated one there; the
periphery is an upsampled image of a camera at twice the pitch, requested one level coarser;
the rays saved are the analytic count; bad input fails in one line."""

import math

import numpy as np
import pytest

from gigascroll import runtime
from gigascroll import views as v
from gigascroll.gallery import builtin_room
from gigascroll.walk.foveation import FoveatedDisplay, Foveation, crop_camera
from gigascroll.walk.gallery_walk import ExhibitionSource, GalleryWalk, parent_keys, walk_path
from gigascroll.views.exhibition import Headset

W, H = 96, 104
HEADSET = Headset(width=W, height=H)
# The angle whose fovea is exactly 32 x 32 pixels of a 96 x 104 eye (W * t / tan_half_x = 32).
EXACT_DEG = math.degrees(2 * math.atan(32 / W * HEADSET.tan_half_x))


@pytest.fixture(scope="module")
def setup(small_scroll_pack):
    """The unlit scroll room, the walk's first pose, and a VT holding every tile the
    unfoveated and the foveated frames ask for (so differences are the foveation's)."""
    pack = small_scroll_pack
    room = builtin_room("scroll", pack)
    src = ExhibitionSource(room, pack)
    path = walk_path(room, seconds=0.6)
    views = v.frame_cameras(path, 0, headset=HEADSET, magnifier=None)
    vt = runtime.VirtualTexture(pack, (40, 40))
    levels = np.array([t.levels for t in src.tiles], np.int64)
    fb = []
    for f in (Foveation(30), Foveation(30, 4), Foveation(EXACT_DEG)):
        fb += f.feedback_views(views)
    keys = np.unique(np.concatenate([src.feedback(c, fw, fh).ravel()
                                     for c, fw, fh in views + fb]))
    keys = keys[keys != v.NO_REQUEST]
    keys = np.concatenate([keys, parent_keys(keys, levels)])
    for key in zip(*(a.tolist() for a in v.unpack_requests(vt.request(keys)))):
        vt.insert(key, pack.read_tile(*key))
    assert vt.request(keys).size == 0
    return src, vt, views[0][0], views[1][0], path, pack, room


def _levels(keys):
    k = np.asarray(keys, np.uint64).ravel()
    k = k[k != v.NO_REQUEST]
    return ((k >> np.uint64(32)) & np.uint64(0x1F)).astype(float)


def test_crop_camera_traces_the_eyes_rays(setup):
    _, _, left, _, _, _, _ = setup
    lay = Foveation(30).layout(left)
    crop = lay.fovea
    assert crop is not None and (crop.width, crop.height) == (lay.fovea_width, lay.fovea_height)
    for x, y in [(0, 0), (crop.width - 1, 0), (3, crop.height - 1), (crop.width // 2, 7),
                 (crop.width - 1, crop.height - 1)]:
        for dx, dy in [(0.5, 0.5), (0.0, 0.0), (0.25, 0.9)]:
            a = np.array(crop.direction(x + dx, y + dy))
            b = np.array(left.direction(x + lay.x0 + dx, y + lay.y0 + dy))
            np.testing.assert_allclose(a, b, atol=1e-14)
    with pytest.raises(ValueError, match="even"):
        crop_camera(left, W - 1, H)
    with pytest.raises(ValueError, match="fit"):
        crop_camera(left, W + 2, H)


def test_fovea_equals_the_unfoveated_frame(setup):
    src, vt, left, right, _, _, _ = setup
    from gigascroll import _core
    plain = _core.DisplayPass()
    fd = FoveatedDisplay(Foveation(30))
    # Without reuse both eyes are traced per pixel: the fovea's pixels are the eye's.
    pl, pr = src.display_stereo(plain, vt, left, right, False)
    fl, fr = fd.display_stereo(src, vt, left, right, False)
    masks = fd.layout.masks()
    assert masks["fovea"].sum() > 200 and masks["band"].any()
    for a, b in ((pl, fl), (pr, fr)):
        np.testing.assert_allclose(b[masks["fovea"]], a[masks["fovea"]], rtol=1e-6, atol=1e-7)
        assert np.abs(b - a)[masks["periphery"]].max() > 0.01  # the periphery is not the eye
    # With reuse the left eye is still traced per pixel.
    pl, _ = src.display_stereo(plain, vt, left, right, True)
    fl, _ = fd.display_stereo(src, vt, left, right, True)
    np.testing.assert_allclose(fl[masks["fovea"]], pl[masks["fovea"]], rtol=1e-6, atol=1e-7)


def _interp_up(low, width, height, factor):
    """An independent bilinear upsampling (np.interp per axis, edge-clamped) of a centred
    image `factor` times coarser."""
    def axis(n_out, n_in):
        return (np.arange(n_out) + 0.5 - n_out / 2) / factor + n_in / 2 - 0.5
    ys, xs = axis(height, low.shape[0]), axis(width, low.shape[1])
    rows = np.stack([np.stack([np.interp(ys, np.arange(low.shape[0]), low[:, x, c])
                               for c in range(3)], -1) for x in range(low.shape[1])], 1)
    return np.stack([np.stack([np.interp(xs, np.arange(low.shape[1]), rows[y, :, c])
                               for c in range(3)], -1) for y in range(height)], 0)


def test_periphery_is_the_coarse_camera_upsampled_and_its_error_is_bounded(setup):
    src, vt, left, right, _, _, _ = setup
    from gigascroll import _core
    fov = Foveation(30)
    lay = fov.layout(left)
    fl, _ = FoveatedDisplay(fov).display_stereo(src, vt, left, right, False)
    # Independently: the camera at twice the pitch, rendered alone and upsampled with np.interp.
    k = 2
    lw, lh = -(-W // k), -(-H // k)
    coarse = v.Camera(tuple(left.position), tuple(left.forward), tuple(left.up),
                      left.tan_half_x * lw * k / W, left.tan_half_y * lh * k / H, lw, lh)
    low = src.display(_core.DisplayPass(), vt, coarse)
    want = _interp_up(low, W, H, k)
    masks = lay.masks()
    per = masks["periphery"]
    np.testing.assert_allclose(fl[per], want[per], atol=2e-6)
    # Against the unfoveated frame: nonzero on the textured painting, and bounded by the
    # error of showing the whole eye one level coarser (lod bias +1) as a yardstick.
    plain = src.display(_core.DisplayPass(), vt, left)
    coarser = _core.DisplayPass().render(src.scene, src.lighting, vt, left, lod_bias=1.0)
    err = np.abs(fl - plain)[per].mean()
    yardstick = np.abs(coarser - plain)[per].mean()
    assert 0.5 * yardstick < err < 2.0 * yardstick
    assert 0.005 < err < 0.2
    # The blend band lies between: no worse than the periphery next to it.
    assert np.abs(fl - plain)[masks["band"]].mean() <= err * 1.5


def test_composite_in_the_core_matches_numpy(rng):
    for (w, h, k, deg, blend) in [(96, 104, 2, 30, 0.25), (97, 51, 3, 20, 0.5),
                                  (40, 44, 4, 60, 0.0), (17, 16, 2, 5, 0.9)]:
        cam = v.Camera((0, 0, 0), (0, 0, -1), (0, 1, 0), 0.986, 0.986 * h / w, w, h)
        lay = Foveation(deg, k, blend).layout(cam)
        per = rng.random((lay.periphery.height, lay.periphery.width, 3), dtype=np.float32)
        fov = rng.random((lay.fovea_height, lay.fovea_width, 3), dtype=np.float32)
        np.testing.assert_allclose(lay.composite(fov, per), lay.composite_reference(fov, per),
                                   atol=1e-6)
        # Weight 1 inside the band: the fovea's pixels as traced.
        out = lay.composite(fov, per)
        inner = lay.weight == 1.0
        region = out[lay.y0:lay.y0 + lay.fovea_height, lay.x0:lay.x0 + lay.fovea_width]
        assert np.array_equal(region[inner], fov[inner])


def test_periphery_requests_are_coarser_by_log2_factor(setup):
    src, vt, left, right, _, _, _ = setup
    from gigascroll import _core
    views = [(left, W // 8, H // 8), (right, W // 8, H // 8)]
    eye = _levels(src.feedback(left, W // 8, H // 8))
    for factor in (2, 4):
        fb = Foveation(30, factor).feedback_views(views)
        assert len(fb) == 4
        fovea, periphery = _levels(src.feedback(*fb[0])), _levels(src.feedback(*fb[1]))
        assert eye.mean() + math.log2(factor) <= 6  # not clamped at the coarsest level
        assert abs(periphery.mean() - eye.mean() - math.log2(factor)) < 0.15
        assert abs(fovea.mean() - eye.mean()) < 0.15
        # The display pass samples the same: lod + log2(factor) at every painting pixel.
        d = _core.DisplayPass()
        src.display(d, vt, Foveation(30, factor).layout(left).periphery)
        coarse = np.nanmean(d.lods(0))
        src.display(d, vt, left)
        assert abs(coarse - np.nanmean(d.lods(0)) - math.log2(factor)) < 0.02


def test_traced_rays_are_the_analytic_count(setup):
    src, vt, left, right, _, _, _ = setup
    fov = Foveation(EXACT_DEG)
    lay = fov.layout(left)
    assert (lay.fovea_width, lay.fovea_height) == (32, 32)
    fd = FoveatedDisplay(fov)
    fd.display_stereo(src, vt, left, right, False)
    analytic = 32 * 32 + (W // 2) * (H // 2)   # fovea pixels + the periphery's pixels
    assert fd.left_stats["traced"] == fd.right_stats["traced"] == analytic == lay.traced_pixels
    assert analytic / (W * H) == pytest.approx(3520 / 9984)
    # With reuse the right eye traces fewer, never more.
    fd.display_stereo(src, vt, left, right, True)
    assert fd.left_stats["traced"] == analytic
    assert fd.right_stats["traced"] + fd.right_stats["reused"] == analytic
    assert fd.right_stats["traced"] < analytic


def test_foveated_walk_converges_to_its_oracle(setup):
    src, _, _, _, path, pack, _ = setup
    walk = GalleryWalk(src, pack, path, eye=(W, H), per_frame=4, wait_loads=True,
                       slots=(24, 24), foveation=Foveation(EXACT_DEG), magnifier=False)
    plain = GalleryWalk(src, pack, path, eye=(W, H), per_frame=4, wait_loads=True,
                        slots=(24, 24), magnifier=False, oracle=False)
    s, sp = walk.run(), plain.run()
    assert walk.records[-1]["error"] == 0.0 and walk.records[-1]["hit_rate"] == 1.0
    assert all(r["traced_rays"] <= 2 * 3520 for r in walk.records)
    assert all(r["traced_rays"] > 9984 for r in plain.records)
    assert s["requests_per_frame"] < sp["requests_per_frame"]


@pytest.mark.parametrize("kwargs, match", [
    ({"fovea_deg": float("nan")}, "angle"), ({"fovea_deg": 0.0}, "angle"),
    ({"fovea_deg": -5.0}, "angle"), ({"fovea_deg": 180.0}, "angle"),
    ({"fovea_deg": float("inf")}, "angle"), ({"fovea_deg": "30"}, "angle"),
    ({"factor": 0}, "factor"), ({"factor": 1}, "factor"), ({"factor": 2.5}, "factor"),
    ({"factor": 99}, "factor"), ({"blend": 1.0}, "blend"), ({"blend": float("nan")}, "blend"),
])
def test_bad_foveation(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Foveation(**kwargs)


def test_fovea_wider_than_the_eye(setup):
    src, _, left, _, path, pack, _ = setup
    with pytest.raises(ValueError, match="narrower"):
        Foveation(90).layout(left)   # the eye is 89.2 degrees wide
    with pytest.raises(ValueError, match="narrower"):
        GalleryWalk(src, pack, path, eye=(W, H), foveation=Foveation(120))


@pytest.mark.parametrize("args, message", [
    (["--fovea", "nan"], "--fovea"), (["--fovea", "0"], "--fovea"),
    (["--fovea", "95"], "narrower"), (["--fovea", "30", "--fovea-factor", "0"], "factor"),
])
def test_gallery_command_bad_fovea(gigascroll_cli, tmp_path, args, message):
    r = gigascroll_cli("gallery", "--out", tmp_path / "out", *args)
    assert r.returncode == 2
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and message in lines[0] and "Traceback" not in r.stderr
    assert not (tmp_path / "out").exists()
