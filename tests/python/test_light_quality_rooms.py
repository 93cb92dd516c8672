"""The quality knob on rooms its rule was not fitted on (it was fitted on the built-in scroll
and hall): the example glTF room, and a room made here (walls at another scale, a painting in a
corner, two lights of other sizes). At each level the mottle (gallery.mottle: RMS relative
error of the blurred luminance per kind of surface) against an independent reference, Mitsuba
3's path tracer at modest spp, stays within FACTOR of the level's stated target
(quality.ERROR_TARGETS), and falls from draft to final.

References: small stills (40 x 30), cached under build/gallery-reference/ (keyed by
everything they depend on, as `bench gallery`'s); the first run renders them (seconds)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import gigascroll as g
from gigascroll.gallery import Gallery
from gigascroll.gallery.mottle import mottle, pool_segments, surface_segments
from gigascroll.gallery.quality import ERROR_TARGETS, QUALITY_LEVELS, apply_settings, light_settings
from gigascroll.room.spec import PaintingSlot, RoomSpec, Surface

from gallery_checks import quad

ROOT = Path(__file__).resolve().parents[2]
W, H, K = 40, 30, 3
SPP = 2048
# How far a room the rule was not fitted on may stray from the stated target of each level.
FACTOR = 2.0
FLAT_RGB = (200, 196, 188)


def corner_room() -> RoomSpec:
    """7 m x 3.6 m x 5 m (the box of the other tests is 4 x 3 x 4), a 1.2 m x 0.8 m painting
    6 cm from the left wall in the back corner, a 0.3 m square spot above it and a 2.5 m x
    0.4 m strip light down the ceiling's middle."""
    surfaces = []

    def add(name, c, a, b, albedo, emission=(0, 0, 0)):
        v, t = quad(c, a, b)
        surfaces.append(Surface(name, v, t, albedo, emission))

    wall, floor = (0.65, 0.62, 0.58), (0.35, 0.3, 0.25)
    add("floor", (0, 0, 0), (0, 0, 2.5), (3.5, 0, 0), floor)
    add("ceiling", (0, 3.6, 0), (3.5, 0, 0), (0, 0, 2.5), wall)
    add("back", (0, 1.8, -2.5), (3.5, 0, 0), (0, 1.8, 0), wall)
    add("front", (0, 1.8, 2.5), (0, 1.8, 0), (3.5, 0, 0), wall)
    add("left", (-3.5, 1.8, 0), (0, 1.8, 0), (0, 0, 2.5), wall)
    add("right", (3.5, 1.8, 0), (0, 0, 2.5), (0, 1.8, 0), wall)
    add("spot", (-2.6, 3.59, -1.6), (0.15, 0, 0), (0, 0, 0.15), (0.7, 0.7, 0.7), (40.0, 38.0, 34.0))
    add("strip", (0.5, 3.59, 0), (1.25, 0, 0), (0, 0, 0.2), (0.7, 0.7, 0.7), (6.0, 6.0, 6.0))
    slot = PaintingSlot("flat", origin=(-3.44, 2.2, -2.499), u_axis=(1, 0, 0), v_axis=(0, -1, 0),
                        width_m=1.2, height_m=0.8, name="corner")
    return RoomSpec("corner", surfaces, [slot], camera_eye=(1.0, 1.6, 2.0),
                    camera_target=(-2.0, 1.4, -2.5))


def flat_pack(path, names_sizes: dict):
    images = [np.broadcast_to(np.array(FLAT_RGB, np.uint8), (h, w, 3)).copy()
              for w, h in names_sizes.values()]
    return g.build_pack(images, path, tile_size=64, border=2, names=list(names_sizes))


@pytest.fixture(scope="module", params=["corner", "example"])
def room(request, tmp_path_factory):
    d = tmp_path_factory.mktemp(request.param)
    if request.param == "corner":
        pack = flat_pack(d / "flat.pack", {"flat": (300, 200)})
        return corner_room(), pack
    from gigascroll.room.example import EXAMPLE_PAINTINGS, write_example_room
    from gigascroll.room.files import load_room

    pack = flat_pack(d / "flat.pack", {k: (w // 10, h // 10) for k, (w, h) in EXAMPLE_PAINTINGS.items()})
    return load_room(write_example_room(d / "room.glb"), pack), pack


def reference(gal: Gallery, camera) -> np.ndarray:
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    from gigascroll.benchmarks.gallery import cached_reference

    return cached_reference(mi, gal, camera, SPP, ROOT / "build" / "gallery-reference")[0]


def level_mottle(room) -> dict:
    """{level: {class: (rms, reference noise)}} of the room's view at each level."""
    spec, pack = room
    gal = Gallery.from_room(spec, pack)
    vt = g.VirtualTexture(pack, (32, 32))
    cam = gal.camera((W * K, H * K), fov=60.0)
    gal.stream(cam, vt)
    ref = reference(gal, gal.camera((W, H), fov=60.0))
    out, segments = {}, None
    for level in QUALITY_LEVELS:
        apply_settings(gal, light_settings(spec, level), vt, threads=2)
        img, hits = gal.render_display(cam, vt, lighting="baked", hits=True)
        if segments is None:
            segments, classes = surface_segments(spec, hits["position"], hits["slot"])
            segments = pool_segments(segments, K)
        img = img.reshape(H, K, W, K, 3).mean(axis=(1, 3))
        m = mottle(img, ref, segments, classes, sigma=2.0)
        out[level] = {c: (m[c]["rms"], m[c]["reference_noise"]) for c in ("walls", "floor", "paintings")
                      if m.get(c)}
    return out


def test_rooms_not_fitted_on_follow_the_levels_targets(room):
    """The mottle as measured (the reference's noise, 0.3-1.3% here, left in: the bound is the
    stricter for it) within FACTOR of each level's target on walls and floor, paintings at
    final within FACTOR of 0.5%, and draft's walls at least twice as mottled as final's (the
    knob does something). Measured 2026-12-06 (final: 36 sparse final-gather rays), walls /
    floor / paintings in %: corner room 2.6 / 2.1 / 5.0 (draft), 1.4 / 1.2 / 0.75 (preview),
    0.27 / 0.31 / 0.52 (final); example room 6.1 / 3.3 / 4.4, 3.0 / 1.4 / 2.0, 0.43 / 0.22 /
    0.55."""
    measured = level_mottle(room)
    name = room[0].name
    for level in QUALITY_LEVELS:
        for cls in ("walls", "floor"):
            if cls in measured[level]:
                rms = measured[level][cls][0]
                assert rms <= FACTOR * ERROR_TARGETS[level], (name, level, cls, measured[level])
    final = measured["final"]
    if "paintings" in final:
        assert final["paintings"][0] <= FACTOR * 0.005, (name, final)
    assert measured["draft"]["walls"][0] > 2 * final["walls"][0], (name, measured)
