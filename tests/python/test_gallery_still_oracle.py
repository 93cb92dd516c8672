"""A room's still (`Gallery.still`, `gigascroll render --room`) reads the texels an all-resident
virtual texture would: trilinear filtering blends each pixel's level with the next coarser one,
so the still must load that level's tiles too (the walk does: `parent_keys`). Oracle: the same
display pass through a VirtualTexture holding every tile of the pack. The painting is a
high-contrast numpy grid, whose mip levels differ (thin lines fade level by level), so a pixel
that blends with a coarser pinned level instead of its parent shows."""

import math

import numpy as np
import pytest

import gigascroll as g
from gigascroll.gallery import Gallery
from gigascroll.gallery.tile_keys import parent_keys

from gallery_checks import box_room

SIZE = (1024, 512)


@pytest.fixture(scope="module")
def grid_pack(tmp_path_factory):
    """One painting 'grid': 1-texel black lines every 8 texels on white, a red 1-texel line
    every 64 (the next levels average them to greys of different strength)."""
    w, h = SIZE
    img = np.full((h, w, 3), 250, np.uint8)
    img[::8, :] = 0
    img[:, ::8] = 0
    img[::64, :] = (220, 10, 10)
    img[:, 3::64] = (220, 10, 10)
    return g.build_pack([img], tmp_path_factory.mktemp("grid") / "grid.pack", tile_size=32, border=2,
                        names=["grid"])


def all_resident(pack):
    """A VirtualTexture with every tile of the pack inserted (large enough that none is evicted)."""
    keys = [(p, l, tx, ty) for p, painting in enumerate(pack.paintings)
            for l, (nx, ny) in enumerate(painting.level_tiles) for ty in range(ny) for tx in range(nx)]
    side = math.ceil(math.sqrt(len(keys) + 64))
    vt = g.VirtualTexture(pack, (side, side))
    for key in keys:
        vt.insert(key, pack.read_tile(*key))
    assert vt.stats()["resident"] >= len(keys)
    return vt


@pytest.fixture(scope="module")
def gallery(grid_pack):
    return Gallery.from_room(box_room(painting="grid"), grid_pack)


# Oblique views along the painting, close enough that its levels of detail run from 1 to 6
# (only the coarsest tile is pinned).
CAMERAS = [
    ((-0.6, 1.6, -1.2), (0.5, 1.5, -2.0), 60.0, (128, 96)),
    ((-0.7, 1.5, -1.6), (0.3, 1.5, -2.0), 70.0, (128, 96)),
]


@pytest.mark.parametrize("lighting", ["unlit", "baked"])
@pytest.mark.parametrize("pose", range(len(CAMERAS)))
def test_still_equals_the_all_resident_oracle(gallery, grid_pack, pose, lighting):
    eye, target, fov, res = CAMERAS[pose]
    cam = g.Camera(list(eye), list(target), [0, 1, 0], fov, resolution=res)
    if lighting != "unlit" and not gallery.lit:
        gallery.light(g.VirtualTexture(grid_pack), photons=20_000, seed=1)
        gallery.bake(spacing=0.25, light_samples=4)
    still = gallery.still(cam, lighting=lighting)
    oracle = gallery.render_display(cam, all_resident(grid_pack), lighting=lighting)
    on_painting = gallery.render_display(cam, g.VirtualTexture(grid_pack), lighting="unlit",
                                         hits=True)[1]["slot"] >= 0
    assert on_painting.mean() > 0.3
    assert np.abs(still - oracle).max() <= 1e-6 * max(1.0, float(oracle.max()))


def test_requested_levels_alone_differ_from_the_oracle(gallery, grid_pack):
    """The check above can fail: a still that loads only the requested tiles (the old stream)
    differs from the oracle on the painting, and loading their parents as well removes it."""
    eye, target, fov, res = CAMERAS[0]
    cam = g.Camera(list(eye), list(target), [0, 1, 0], fov, resolution=res)
    keys = gallery.render_view(cam, width=res[0], height=res[1])["keys"]
    keys = np.unique(keys[keys != g.NO_REQUEST])
    levels = np.array([p.levels for p in grid_pack.paintings], np.int64)
    parents = parent_keys(keys, levels)
    assert len(np.setdiff1d(parents, keys)) > 0

    def still_with(wanted):
        vt = g.VirtualTexture(grid_pack, (48, 48))
        for key in zip(*(a.tolist() for a in g.unpack_requests(vt.request(wanted)))):
            vt.insert(key, grid_pack.read_tile(*key))
        return gallery.render_display(cam, vt, lighting="unlit")

    oracle = gallery.render_display(cam, all_resident(grid_pack), lighting="unlit")
    requested_only = np.abs(still_with(keys) - oracle).max(axis=2)
    assert (requested_only > 0.01 * oracle.max()).mean() > 0.01
    assert np.abs(still_with(np.concatenate([parents, keys])) - oracle).max() <= 1e-6
