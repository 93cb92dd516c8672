"""`gigascroll render --room`: the scene renderer's options either apply to the room's still or
are refused with one line (exit 2); none is ignored.

Applied: --no-indirect (no photon pass: direct light only), --spp (k x k supersampling),
--light-samples, --disc / --sphere, with --photons, --radius, --seed, --threads as before.
Refused: --progressive, --passes, --time-budget, --kernel cone, --grid hash|kdtree,
--gather knn, -k, --pipeline two-pass, --cooperative.

References: the emitter's irradiance on the floor by brute-force numpy integration over the
light, zero where no light arrives directly (the ceiling above a downward light), and a
64-spp still for the convergence of --spp. The fuzz family throws random combinations of the
options at the command: exit 0, or 2 with one line."""

from __future__ import annotations

import numpy as np
import pytest
from fuzz_support import CASES, cli_message_ok, count_case, fork_worker, fuzz_settings  # noqa: F401
from hypothesis import given
from hypothesis import strategies as st

import gigascroll as g
from gigascroll.gallery import Gallery

from gallery_checks import box_room, example_room_files, gradient_pack

LIGHT = 5.0  # box_room's light: radiance 5, a 1 m square at y = 2.999 facing down


def floor_irradiance(x: np.ndarray, z: np.ndarray, n: int = 100) -> np.ndarray:
    """E at floor points (x, 0, z) from box_room's light, by the midpoint rule over the light."""
    s = (np.arange(n) + 0.5) / n - 0.5
    lx, lz = np.meshgrid(s, s)
    h = 2.999
    dx = lx.ravel()[None, :] - x.ravel()[:, None]
    dz = lz.ravel()[None, :] - z.ravel()[:, None]
    r2 = dx * dx + dz * dz + h * h
    return (LIGHT * h * h / (r2 * r2)).sum(axis=1).reshape(x.shape) / (n * n)


@pytest.fixture(scope="module")
def pack(tmp_path_factory):
    return gradient_pack(tmp_path_factory.mktemp("room") / "g.pack", size=(256, 128))


def room_still(pack, camera, lighting, **options):
    """The still with light(**options) and, for "baked", a bake at 10 cm (quicker than the
    default's 3 cm: the room's light varies over metres)."""
    gallery = Gallery.from_room(box_room(painting="gradient"), pack)
    gallery.light(g.VirtualTexture(pack), **options)
    if lighting == "baked":
        gallery.bake(spacing=0.1)
    return gallery, gallery.still(camera, lighting=lighting)


def down_camera(res=(48, 36)):
    """From above the floor's middle, looking down and away from the light."""
    return g.Camera([0.0, 1.2, 1.0], [0.0, 0.0, -0.5], [0, 1, 0], 60.0, resolution=res)


@pytest.mark.parametrize("lighting", ["baked", "full"])
def test_no_indirect_is_the_emitters_direct_light_alone(pack, lighting):
    cam = down_camera()
    gallery, still = room_still(pack, cam, lighting, photons=20_000, indirect=False)
    assert gallery.stats["photons_stored"] == 0
    vt = g.VirtualTexture(pack)
    _, hits = gallery.render_display(cam, vt, lighting=lighting, hits=True)
    np.testing.assert_array_equal(still, gallery.render_display(cam, vt, lighting=lighting))
    pos, E = hits["position"], hits["irradiance"][..., 0].astype(np.float64)
    floor = np.abs(pos[..., 1]) < 1e-4
    assert floor.sum() > 500
    exact = floor_irradiance(pos[..., 0][floor], pos[..., 2][floor])
    if lighting == "baked":  # the ratio estimator is exact in full view; the lattice interpolates
        np.testing.assert_allclose(E[floor], exact, rtol=0.01)
    else:  # independent emitter samples per pixel: their mean
        assert E[floor].mean() == pytest.approx(exact.mean(), rel=0.01)
    # with indirect light the floor is brighter by what the walls reflect
    lit, lit_still = room_still(pack, cam, lighting, photons=20_000)
    assert lit.stats["photons_stored"] > 0
    assert lit_still[floor].mean() > 1.05 * still[floor].mean()


def test_no_indirect_leaves_what_no_light_reaches_directly_black(pack):
    """The ceiling beside a downward light gets only reflected light: zero without it."""
    cam = g.Camera([0.0, 1.5, 1.5], [0.0, 3.0, -0.8], [0, 1, 0], 60.0, resolution=(40, 30))
    gallery, direct = room_still(pack, cam, "baked", photons=20_000, indirect=False)
    _, hits = gallery.render_display(cam, g.VirtualTexture(pack), lighting="unlit", hits=True)
    ceiling = np.abs(hits["position"][..., 1] - 3.0) < 1e-4
    assert ceiling.sum() > 200
    assert np.all(direct[ceiling] == 0)
    _, full = room_still(pack, cam, "baked", photons=20_000)
    assert np.all(full[ceiling].sum(axis=-1) > 0)


def test_spp_converges_to_the_high_spp_still(pack):
    """Lighting "full" (its emitter samples are noise): the still's distance to a 64-spp still
    shrinks with spp, about as 1 / sqrt(spp) until the reference's own noise shows."""
    cam = g.Camera([0.4, 1.4, 0.8], [-0.2, 1.3, -2.0], [0, 1, 0], 50.0, resolution=(32, 24))
    gallery = Gallery.from_room(box_room(painting="gradient"), pack)
    gallery.light(g.VirtualTexture(pack), photons=20_000, light_samples=2, seed=3)
    ref = gallery.still(cam, lighting="full", spp=64)
    err = {spp: float(np.sqrt(np.mean((gallery.still(cam, lighting="full", spp=spp) - ref) ** 2)))
           for spp in (1, 4, 16)}
    # measured 0.0115, 0.0055, 0.0032 (the reference's own noise slows the last step)
    assert err[1] > 1.6 * err[4] and err[4] > 1.4 * err[16], err
    # the mean is kept: supersampling averages, it does not brighten or darken
    one = gallery.still(cam, lighting="full", spp=1)
    assert one.mean() == pytest.approx(ref.mean(), rel=0.02)


def test_spp_must_be_a_square(pack):
    gallery = Gallery.from_room(box_room(painting="gradient"), pack)
    for bad in (0, 2, 5, -4, 2.0, True):
        with pytest.raises(ValueError, match="square"):
            gallery.still(down_camera((8, 6)), lighting="unlit", spp=bad)


# ------------------------------------------------------------------------------- the CLI

@pytest.fixture(scope="module")
def room_files(tmp_path_factory):
    return example_room_files(tmp_path_factory.mktemp("cli"))


BASE = ["--width", "24", "--height", "18", "--photons", "3000", "--threads", "1"]


def cli_exr(fork_worker, room_files, name, *options):
    oiio = pytest.importorskip("OpenImageIO")
    out = room_files / f"{name}.exr"
    argv = ["render", "--room", str(room_files / "room.glb"), "--pack", str(room_files / "ex.pack"),
            "-o", str(out), *BASE, *options]
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=120)
    assert o.code == 0, o.describe()
    img = oiio.ImageInput.open(str(out))
    data = img.read_image("float")
    img.close()
    return data, o.stdout


def api_still(room_files, lighting="baked", spp=None, **options):
    """The still as the API makes it: the knob's default settings for the room
    (gallery/quality.py), the options over them, photons=3000 as BASE."""
    from gigascroll.gallery.quality import light_settings
    from gigascroll.room.files import load_room

    pack = g.TilePack(room_files / "ex.pack")
    gallery = Gallery.from_room(load_room(room_files / "room.glb", pack), pack)
    cam = gallery.camera((24, 18))
    s = light_settings(gallery.spec)
    if lighting != "unlit":
        gallery.light(g.VirtualTexture(pack, (30, 30)),
                      **{**s.light_options(), "photons": 3000, "threads": 1, "seed": 0, **options})
        if lighting == "baked":
            bake = {**s.bake_options(), **({"light_samples": options["light_samples"]}
                                           if "light_samples" in options else {})}
            gallery.bake(threads=1, **bake)
    return gallery.still(cam, lighting=lighting, spp=spp or s.spp)


@pytest.mark.parametrize("options, api", [
    ((), {}),
    (("--no-indirect",), {"indirect": False}),
    (("--spp", "4"), {"spp": 4}),
    (("--light-samples", "3", "--lighting", "full"), {"light_samples": 3, "lighting": "full"}),
    (("--disc",), {"disc": True}),
])
def test_applied_options_reach_the_still(fork_worker, room_files, options, api):
    """Each applied option gives the API's still with that option, and (but for the default)
    an image other than the default's: nothing is ignored."""
    got, stdout = cli_exr(fork_worker, room_files, "applied", *options)
    np.testing.assert_array_equal(got, api_still(room_files, **api))
    if options:
        lighting = api.get("lighting", "baked")
        default = api_still(room_files, lighting=lighting)
        assert not np.array_equal(got, default), options
    if "--no-indirect" in options:
        assert "skipped" in stdout and "emitted" not in stdout


@pytest.mark.parametrize("options, match", [
    (["--progressive"], "--progressive"),
    (["--passes", "4"], "--passes"),
    (["--time-budget", "1"], "--time-budget"),
    (["--kernel", "cone"], "--kernel cone"),
    (["--grid", "hash"], "--grid hash"),
    (["--gather", "knn"], "--gather knn"),
    (["-k", "10"], "-k"),
    (["--pipeline", "two-pass"], "--pipeline two-pass"),
    (["--cooperative"], "--cooperative"),
    (["--spp", "2"], "square"),
    (["--spp", "0"], "square"),
    (["--width", "8192", "--height", "8192", "--spp", "4"], "2^26"),
    (["--light-samples", "0"], "--light-samples"),
])
def test_refused_options_exit_2_with_one_line(fork_worker, room_files, options, match):
    out = room_files / "refused.exr"
    argv = ["render", "--room", str(room_files / "room.glb"), "--pack", str(room_files / "ex.pack"),
            "-o", str(out), *BASE, *options]
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=60)
    assert o.code == 2 and cli_message_ok(o) is None, o.describe()
    assert match in o.stderr, o.stderr
    if match not in ("square", "2^26", "--light-samples"):
        assert "does not apply to --room" in o.stderr, o.stderr
    assert not out.exists()


OPTIONS = st.lists(st.sampled_from([
    ["--no-indirect"], ["--spp", "1"], ["--spp", "4"], ["--spp", "3"], ["--spp", "-9"],
    ["--light-samples", "1"], ["--light-samples", "5000"], ["--light-samples", "nan"],
    ["--disc"], ["--sphere"], ["--progressive"], ["--passes", "2"], ["--time-budget", "nan"],
    ["--kernel", "box"], ["--kernel", "cone"], ["--grid", "adaptive"], ["--grid", "kdtree"],
    ["--gather", "radius"], ["--gather", "knn"], ["-k", "0"], ["--pipeline", "fused"],
    ["--cooperative"], ["--lighting", "full"], ["--lighting", "unlit"], ["--radius", "0"],
    ["--radius", "1e-30"], ["--radius", "inf"], ["--seed", "7"], ["--photons", "1"],
]), max_size=4)


@fuzz_settings(12)
@given(options=OPTIONS)
def test_random_option_combinations(fork_worker, room_files, options):
    count_case("render --room options")
    out = room_files / "fuzz.png"
    argv = ["render", "--room", str(room_files / "room.glb"), "--pack", str(room_files / "ex.pack"),
            "-o", str(out), "--width", "12", "--height", "9", "--photons", "500", "--threads", "1",
            *[a for o in options for a in o]]
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=120)
    problem = cli_message_ok(o)
    assert problem is None, f"{problem}: {argv}\n{o.describe()}"
    if o.code == 0:
        assert out.exists()
        out.unlink()


# ------------------------------------------------------------------ the API: render(Gallery)

def test_render_of_a_gallery_applies_or_refuses_the_same_options(pack):
    """gigascroll.render(gallery, ...) is the still with the options the gallery has, and a
    ValueError for the others (they were ignored too)."""
    cam = down_camera((16, 12))
    for bad in (dict(progressive=True), dict(kernel="cone"), dict(grid="hash"), dict(gather="knn"),
                dict(pipeline="two-pass"), dict(direct=False), dict(final_gather=True)):
        gallery = Gallery.from_room(box_room(painting="gradient"), pack)
        with pytest.raises(ValueError, match="does not have"):
            g.render(gallery, cam, photons=2000, **bad)
        assert not gallery.lit  # refused before any work
    for options in (dict(indirect=False), dict(spp=4), dict(disc=True), dict(light_samples=3)):
        a = Gallery.from_room(box_room(painting="gradient"), pack)
        b = Gallery.from_room(box_room(painting="gradient"), pack)
        got = g.render(a, cam, photons=2000, lighting="full", **options)
        want = b.still(cam, lighting="full", photons=2000, seed=0, threads=0, **options)
        np.testing.assert_array_equal(got, want)
        c = Gallery.from_room(box_room(painting="gradient"), pack)
        assert not np.array_equal(got, g.render(c, cam, photons=2000, lighting="full")), options
