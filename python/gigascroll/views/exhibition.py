"""The exhibition: the headset's eyes and the magnifier, the test paintings (the scroll and
VT-mobile-VR's Table 4, all scanned at the scroll's texel size) and the two rooms of VT-mobile-VR
sections 5.3 and 5.4.

Units are metres; y is up. A painting hanging on a wall faces -z; paintings on tables face +y.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .._core import ExhibitionScene, PaintingGeometry, ResidentSet
from ..errors import expect_type

__all__ = ["HEADSET", "MAGNIFIER", "SCROLL", "TABLE4_PAINTINGS", "Headset", "Magnifier",
           "PaintingSpec", "Exhibition", "single_scroll", "multi_exhibition", "FPS", "TEXEL_M",
           "spec_of"]

FPS = 90.0  # the headset's display rate


@dataclass(frozen=True)
class Headset:
    """Per-eye display of the seed's headset (Quest Pro: 1800 x 1920 per eye, IPD 63 mm).

    The seed gives no field of view; it says level 0 of the 152089-texel, 12 m scroll is only
    seen from about 7.2 cm. We take that as one texel per display pixel at 7.2 cm on the view
    axis: tan(fov_x / 2) = 900 * (12 / 152089) / 0.072 = 0.986 (89.2 degrees), square pixels
    give tan(fov_y / 2) = 1.052 (92.9 degrees). With it the eye asks level 2 at 40 cm, as in
    the seed's Table 2 set-up.
    """
    width: int = 1800
    height: int = 1920
    tan_half_x: float = 900 * (12.0 / 152089) / 0.072
    ipd: float = 0.063
    feedback_scale: int = 8  # feedback pass at 1/8 of the display per axis

    @property
    def tan_half_y(self) -> float:
        return self.tan_half_x * self.height / self.width


@dataclass(frozen=True)
class Magnifier:
    """The magnifier: a camera at the lens, between the eye and the painting, whose narrow
    field shows `field` metres of painting (2.5 cm) on a 512 x 512 target that the 10 cm lens
    displays; its feedback runs at full 512 x 512."""
    field: float = 0.025
    lens_size: float = 0.10
    resolution: int = 512
    lens_distance: float = 0.20  # lens-to-painting distance (midway for the 40 cm view)


HEADSET = Headset()
MAGNIFIER = Magnifier()


@dataclass(frozen=True)
class PaintingSpec:
    name: str
    width: int   # texels
    height: int
    width_m: float
    height_m: float

    def tiles(self, tile_size: int = 128, border: int = 4) -> PaintingGeometry:
        return PaintingGeometry(self.width, self.height, tile_size, border)


# Every painting is scanned at the scroll's resolution: 12 m over 152089 texels.
TEXEL_M = 12.0 / 152089


def spec_of(name: str, width: int, height: int) -> PaintingSpec:
    """A painting of width x height texels at the scroll's texel size."""
    return PaintingSpec(name, width, height, width * TEXEL_M, height * TEXEL_M)


SCROLL = PaintingSpec("qianli_jiangshan", 152089, 6083, 12.0, 0.5)  # 12 m x 0.5 m (VT-mobile-VR)
# VT-mobile-VR Table 4 (the first is the scroll itself).
TABLE4_PAINTINGS = [SCROLL] + [spec_of(f"table4_{i}", w, h) for i, (w, h) in enumerate(
    [(196301, 5197), (159010, 4339), (102680, 5229), (109321, 7183), (117968, 4722),
     (91403, 11161), (119177, 3858)], start=1)]


@dataclass
class Exhibition:
    """A committed scene plus what request processing needs to know about its paintings."""
    scene: ExhibitionScene
    specs: list[PaintingSpec]          # by painting id
    tiles: list[PaintingGeometry]         # by painting id
    placements: list[dict] = field(default_factory=list)

    def resident_set(self) -> ResidentSet:
        return ResidentSet(self.tiles)


def single_scroll(spec: PaintingSpec = SCROLL, tile_size: int = 128, border: int = 4,
                  centre_height: float = 1.5) -> Exhibition:
    """VT-mobile-VR §5.3: one scroll on a wall (a box behind it) in the plane z = 0 from
    x = 0 to width_m, seen from z < 0; the top edge at centre_height + height_m / 2. Texel
    (0, 0) is the top-left corner as a visitor sees it, at x = width_m: a camera looking +z
    has its right along -x, so image x runs along -x (with u = +x it would read mirrored)."""
    expect_type(spec, PaintingSpec, "single_scroll: spec")
    tiles = spec.tiles(tile_size, border)
    scene = ExhibitionScene()
    top = centre_height + spec.height_m / 2
    scene.add_painting(0, tiles, (spec.width_m, top, 0.0), (-1.0, 0.0, 0.0), (0.0, -1.0, 0.0),
                       spec.width_m, spec.height_m)
    scene.add_box((-2.0, 0.0, 0.005), (spec.width_m + 2.0, 3.0, 0.2))  # the wall
    scene.add_box((-2.0, -0.1, -4.0), (spec.width_m + 2.0, 0.0, 0.2))  # the floor
    scene.commit()
    return Exhibition(scene, [spec], [tiles], [scene.painting(0)])


def multi_exhibition(n_paintings: int, specs: list[PaintingSpec] | None = None,
                     tile_size: int = 128, border: int = 4, table_height: float = 0.70,
                     gap: float = 0.10) -> Exhibition:
    """VT-mobile-VR §5.4: the eight Table 4 paintings in copies (painting id i shows
    specs[i % 8]), eight to a table, laid flat on tables 70 cm high. Table g runs along x at
    z from 1 + g * (depth + 1) m; its paintings lie side by side across it, long side along x,
    image top towards -z (towards the visitor)."""
    specs = specs or TABLE4_PAINTINGS
    if n_paintings < 1 or n_paintings % len(specs):
        raise ValueError(f"n_paintings must be a positive multiple of {len(specs)}, "
                         f"got {n_paintings}")
    tiles_of = [s.tiles(tile_size, border) for s in specs]
    length = max(s.width_m for s in specs) + 2 * gap
    depth = sum(s.height_m for s in specs) + (len(specs) + 1) * gap
    scene = ExhibitionScene()
    all_specs, all_tiles = [], []
    for g in range(n_paintings // len(specs)):
        z0 = 1.0 + g * (depth + 1.0)
        scene.add_table(length / 2, z0 + depth / 2, length, depth, table_height)
        z = z0 + gap
        for i, s in enumerate(specs):
            pid = g * len(specs) + i
            # Painting plane 1 mm above the table top; u along +x, v (image down) along +z.
            scene.add_painting(pid, tiles_of[i], (gap, table_height + 0.001, z), (1.0, 0.0, 0.0),
                               (0.0, 0.0, 1.0), s.width_m, s.height_m)
            all_specs.append(s)
            all_tiles.append(tiles_of[i])
            z += s.height_m + gap
    scene.add_box((-5.0, -0.1, -5.0), (length + 5.0, 0.0, 1.0 + 5 * (depth + 1.0) + 5.0))
    scene.commit()
    return Exhibition(scene, all_specs, all_tiles,
                      [scene.painting(i) for i in range(scene.painting_count)])
