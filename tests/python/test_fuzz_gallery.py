"""Fuzz cases for Gallery.from_room and render_display: hostile rooms give ValueError, any
camera gives finite non-negative radiance, and concurrent relighting cannot tear a frame."""

import math
import threading

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import gigascroll as g
from gigascroll.gallery import Gallery, PaintingSlot, RoomSpec, Surface

from gallery_checks import box_room, uniform_pack

FUZZ = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
floats = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=64),
                   st.floats(-10, 10), st.sampled_from([0.0, -0.0, 1.0, 0.999999, 1e-30, 1e30]))


@pytest.fixture(scope="module")
def pack(tmp_path_factory):
    return uniform_pack(tmp_path_factory.mktemp("fuzzgal") / "p.pack", {"red": (230, 30, 20)}, size=(64, 32),
                        tile_size=16)


@pytest.fixture(scope="module")
def lit(pack):
    gal = Gallery.from_room(box_room(), pack)
    vt = g.VirtualTexture(pack)
    gal.light(vt, photons=5000)
    gal.bake(spacing=0.5, light_samples=2)
    return gal, vt


@FUZZ
@given(vertices=st.lists(st.tuples(floats, floats, floats), min_size=1, max_size=6),
       triangles=st.lists(st.tuples(*[st.integers(-2, 8)] * 3), min_size=1, max_size=4),
       albedo=st.tuples(floats, floats, floats), emission=st.tuples(floats, floats, floats),
       painting=st.one_of(st.integers(-3, 3), st.text(max_size=5), st.none(), st.floats(), st.booleans()),
       axis=st.tuples(floats, floats, floats), size=floats)
def test_from_room_refuses_or_builds(pack, vertices, triangles, albedo, emission, painting, axis, size):
    spec = box_room()
    spec.surfaces.append(Surface("fuzz", np.array(vertices, float), np.array(triangles), albedo, emission))
    spec.paintings.append(PaintingSlot(painting, origin=(0, 1, 0), u_axis=axis, v_axis=(0, 1, 0),
                                       width_m=size, height_m=1.0))
    try:
        gal = Gallery.from_room(spec, pack)
    except ValueError:
        return
    assert gal.committed and gal.painting_count == 2


@FUZZ
@given(eye=st.tuples(*[st.floats(-5, 5)] * 3), target=st.tuples(*[st.floats(-5, 5)] * 3),
       fov=st.floats(1, 170), w=st.integers(1, 12), h=st.integers(1, 12),
       lighting=st.sampled_from(["unlit", "baked", "full"]))
def test_any_camera_gives_finite_radiance(lit, eye, target, fov, w, h, lighting):
    gal, vt = lit
    if np.linalg.norm(np.subtract(eye, target)) < 1e-3:
        return
    try:
        cam = g.Camera(list(eye), list(target), [0, 1, 0], fov, resolution=(w, h))
    except ValueError:
        return  # looking straight up or down: the camera refuses the degenerate frame
    rgb, hits = gal.render_display(cam, vt, lighting=lighting, hits=True)
    assert rgb.shape == (h, w, 3) and np.isfinite(rgb).all() and (rgb >= 0).all()
    # Without hits, baked runs the packet display pass: finite, and the per-pixel path's
    # pixels up to float rounding (a silhouette pixel may land on the other side of an edge).
    fast = gal.render_display(cam, vt, lighting=lighting)
    assert fast.shape == (h, w, 3) and np.isfinite(fast).all() and (fast >= 0).all()
    far = ~np.isclose(fast, rgb, rtol=1e-3, atol=1e-5).all(axis=2)
    assert far.sum() <= max(1, far.size // 10)
    on = hits["slot"] >= 0
    assert ((hits["uv"][on] >= 0) & (hits["uv"][on] <= 1)).all()
    fb = gal.render_view(cam, width=w, height=h)
    assert fb["keys"].shape == (h, w)


def test_open_room_seen_from_outside_displays_black_where_nothing_is_hit(pack):
    """A room without its ceiling and front wall, seen from outside and above: most rays miss.
    The packet display pass (the still, the walk's one eye and its stereo pair) read the baked
    lattice in every lane of a 16-ray packet, and a missed lane's barycentrics are whatever
    Embree left there: they once indexed outside the lattice and crashed. Against the
    per-pixel path; missed pixels are 0."""
    from gigascroll import _core
    spec = box_room()
    spec.surfaces = [s for s in spec.surfaces if s.name not in ("ceiling", "front")]
    gal = Gallery.from_room(spec, pack)
    vt = g.VirtualTexture(pack)
    gal.light(vt, photons=3000)
    gal.bake(spacing=0.5, light_samples=2)
    for eye, target, (w, h) in (((-4.14, -2.63, 3.01), (0.82, -4.06, -0.67), (2, 9)),
                                 ((0.0, 6.0, 7.0), (0.0, 1.0, -2.0), (37, 23)),
                                 ((0.3, 1.5, 9.0), (0.0, 1.5, 0.0), (64, 40))):
        cam = g.Camera(list(eye), list(target), [0, 1, 0], 80.0, resolution=(w, h))
        ref, hits = gal.render_display(cam, vt, lighting="baked", hits=True)
        missed = ~np.isfinite(hits["position"]).all(axis=2)
        fast = gal.render_display(cam, vt, lighting="baked")
        mono = np.asarray(_core._gallery_display(_core.DisplayPass(), gal, vt, cam, "baked", 0, None))
        right = g.Camera([eye[0] + 0.064, eye[1], eye[2]], [target[0] + 0.064, target[1], target[2]],
                         [0, 1, 0], 80.0, resolution=(w, h))
        left_img, right_img = _core._gallery_display_stereo(_core.DisplayPass(), gal, vt, cam, right, "baked",
                                                            True)
        for img in (fast, mono, np.asarray(left_img), np.asarray(right_img)):
            assert np.isfinite(img).all() and (img >= 0).all()
        assert (fast[missed] == 0).all() and (ref[missed] == 0).all()
        near = np.isclose(fast, ref, rtol=1e-3, atol=1e-5).all(axis=2)
        assert near.mean() > 0.95
        assert np.array_equal(mono, fast) and np.array_equal(np.asarray(left_img), fast)
    assert missed.mean() > 0.2  # the last view looks into the open front: a good part of it misses


def test_hostile_render_arguments(lit, pack):
    gal, vt = lit
    cam = gal.camera((4, 4))
    for bad in (None, "camera", 3):
        with pytest.raises((ValueError, TypeError)):
            gal.render_display(bad, vt)
    with pytest.raises((ValueError, TypeError)):
        gal.render_display(cam, None)
    from pathlib import Path
    other = uniform_pack(Path(pack.path).parent / "other.pack", {"a": (1, 2, 3)}, size=(40, 40), tile_size=16)
    with pytest.raises(ValueError, match="not the one|not in"):
        gal.render_display(cam, g.VirtualTexture(other), lighting="unlit")
    for bad in ("yes", None, 1):
        with pytest.raises(ValueError, match="reference"):
            gal.render_display(cam, vt, lighting="baked", reference=bad)
    for out in (np.zeros((4, 4, 3), np.float32)[:, ::-1], np.zeros((4, 4, 3), np.float32).T,
                np.zeros((4, 4), np.float32)):
        with pytest.raises(ValueError):
            gal.render_display(cam, vt, out=out)
    for kw in ({"photons": -1}, {"photons": 1.5}, {"light_samples": 0}, {"radius": math.inf}):
        with pytest.raises(ValueError):
            gal.light(vt, **kw)


@FUZZ
@given(spacing=st.one_of(st.none(), floats), light_samples=st.one_of(st.integers(-2, 64), st.sampled_from([65537, 1 << 40]), floats),
       gather_stride=st.one_of(st.integers(-1, 4), floats, st.booleans()),
       stratified=st.booleans(), skip_unlit=st.booleans(),
       inset_edges=st.one_of(st.booleans(), st.none(), st.integers(-1, 2), st.text(max_size=3)),
       coarse_disc=st.one_of(st.booleans(), st.none(), st.integers(-1, 2), floats), disc=st.booleans(),
       analytic_direct=st.one_of(st.booleans(), st.none(), st.integers(-1, 2)),
       shadow_probes=st.one_of(st.integers(-2, 40), st.sampled_from([65537, 1 << 40]), floats, st.booleans()),
       fill_covered=st.one_of(st.booleans(), st.none(), st.integers(-1, 2)),
       indirect_filter=st.one_of(floats, st.integers(-2, 20), st.booleans(), st.none()),
       final_gather=st.one_of(st.integers(-2, 20), st.sampled_from([4097, 1 << 40]), floats, st.booleans()))
def test_bake_options_refuse_or_bake_finite_light(pack, spacing, light_samples, gather_stride, stratified,
                                                  skip_unlit, inset_edges, coarse_disc, disc, analytic_direct,
                                                  shadow_probes, fill_covered, indirect_filter, final_gather):
    gal = Gallery.from_room(box_room(), pack)
    vt = g.VirtualTexture(pack)
    gal.light(vt, photons=2000, disc=disc)
    if spacing is not None and isinstance(spacing, float) and math.isfinite(spacing) and spacing > 0:
        spacing = max(spacing, 0.05)  # finer lattices only cost time
    try:
        gal.bake(spacing=spacing, light_samples=light_samples, gather_stride=gather_stride,
                 stratified=stratified, skip_unlit=skip_unlit, inset_edges=inset_edges, coarse_disc=coarse_disc,
                 analytic_direct=analytic_direct, shadow_probes=shadow_probes, fill_covered=fill_covered,
                 indirect_filter=indirect_filter, final_gather=final_gather)
    except ValueError:
        assert not gal.baked
        return
    # Anything else is refused.
    assert isinstance(inset_edges, bool) and isinstance(coarse_disc, bool) and isinstance(analytic_direct, bool)
    assert isinstance(shadow_probes, int) and not isinstance(shadow_probes, bool) and 0 <= shadow_probes <= 1 << 16
    assert isinstance(fill_covered, bool) and not isinstance(indirect_filter, bool) and 0 <= indirect_filter <= 16
    assert isinstance(final_gather, int) and not isinstance(final_gather, bool) and 0 <= final_gather <= 4096
    img = gal.render_display(gal.camera((6, 4)), vt, lighting="baked")
    assert np.isfinite(img).all() and (img >= 0).all() and img.max() > 0


def test_relighting_while_rendering_from_another_thread(pack):
    """light() and bake() exclude render_display: frames rendered meanwhile are whole frames of
    one lighting or the other, never a crash or NaN."""
    gal = Gallery.from_room(box_room(), pack)
    vt = g.VirtualTexture(pack)
    gal.light(vt, photons=5000)
    gal.bake(spacing=0.5, light_samples=2)
    cam = gal.camera((16, 12))
    errors, frames = [], []

    def render():
        try:
            for _ in range(20):
                frames.append(gal.render_display(cam, vt, lighting="baked"))
        except ValueError as e:  # between light() and bake() there is no bake: a clear error
            errors.append(e)

    t = threading.Thread(target=render)
    t.start()
    for seed in range(3):
        gal.light(vt, photons=5000, seed=seed)
        gal.bake(spacing=0.5, light_samples=2)
    t.join()
    assert all("bake" in str(e) for e in errors)
    assert all(np.isfinite(f).all() for f in frames)


def test_huge_feedback_pass_is_refused_before_allocating(lit):
    """The gallery's feedback pass has the exhibition's size bound (2^26 pixels): a 65535^2
    pass would need about 110 GiB and must be refused with the memory named, not attempted."""
    gal, _vt = lit
    cam = gal.camera((4, 4))
    with pytest.raises(ValueError, match=r"would need .*GiB"):
        gal.render_view(cam, width=65535, height=65535)
    with pytest.raises(ValueError, match="out of range"):
        gal.render_view(cam, width=1 << 16, height=4)
    with pytest.raises(ValueError, match="display_step"):
        gal.render_view(cam, width=4, height=4, display_step=0)
    assert gal.render_view(cam, width=4, height=2)["keys"].shape == (2, 4)


@FUZZ
@given(shape=st.lists(st.integers(0, 12), min_size=0, max_size=4),
       dtype=st.sampled_from([np.float32, np.float64, np.int32, np.uint8, np.float16]),
       step=st.integers(1, 2), readonly=st.booleans(), stereo=st.booleans())
@example(shape=[6, 8, 3], dtype=np.float32, step=1, readonly=False, stereo=False)
@example(shape=[6, 8, 3], dtype=np.float32, step=1, readonly=False, stereo=True)
@example(shape=[6, 8, 3], dtype=np.float32, step=2, readonly=False, stereo=True)
def test_display_output_arrays_are_checked(lit, shape, dtype, step, readonly, stereo):
    """Any caller array for the display pass's output: rendered into when it is exactly the
    eye's (h, w, 3) C-contiguous writable float32 image, else ValueError, never a write out
    of bounds."""
    from gigascroll import _core
    gal, vt = lit
    cam = g.Camera((0.5, 1.5, 0.5), (0.5, 1.5, 2.0), (0.0, 1.0, 0.0), 60.0, resolution=(8, 6))
    a = np.zeros([s * (step if i == len(shape) - 1 else 1) for i, s in enumerate(shape)], dtype)
    if shape and step > 1:
        a = a[..., ::step]
    a.flags.writeable = not readonly
    ok = (list(a.shape) == [6, 8, 3] and a.dtype == np.float32 and a.flags.c_contiguous
          and not readonly)
    d = _core.DisplayPass()
    try:
        if stereo:
            _core._gallery_display_stereo(d, gal, vt, cam, cam, "baked",
                                          out_left=np.zeros((6, 8, 3), np.float32), out_right=a)
        else:
            _core._gallery_display(d, gal, vt, cam, "baked", out=a)
    except ValueError:
        assert not ok
        return
    assert ok and np.isfinite(a).all() and (a >= 0).all()
