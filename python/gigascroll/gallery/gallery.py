"""`Gallery`: a `RoomSpec` and the paintings of a pack in the core's one Embree scene.

    pack = gigascroll.TilePack("paintings.pack")
    gallery = Gallery.from_room(spec, pack)         # bind the painting slots, build the BVH
    vt = gigascroll.VirtualTexture(pack)
    gallery.light(vt)                               # photon pass (both cores, GIL released)
    gallery.bake()                                  # irradiance lattice, once per lighting
    rgb = gallery.render_display(camera, vt, lighting="baked")   # (H, W, 3) linear radiance

`render_view(camera, ...)` is the feedback pass on the same scene (request keys, lambda, uv per
pixel, as `gigascroll.render_view`). `render_display(..., hits=True)` also returns, per pixel,
the hit position, painting slot, painting uv and lambda: what a stereo pass needs to reproject
one eye's pixels into the other (irradiance is view-independent; see cpp/gallery/gallery.h).
Lighting modes: "baked" (irradiance interpolated from the lattice of `bake`), "full" (direct
light and photon gather at every pixel: the accurate mode), "unlit" (albedo and emission only).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from .. import _core
from .._core import Camera, TilePack
from ..errors import positive_float32
from ..room.spec import PaintingSlot, RoomSpec, Surface

__all__ = ["Gallery", "LIGHTING_MODES", "PAINTING_REFLECTANCE", "painting_albedo"]

LIGHTING_MODES = ("baked", "full", "unlit")
# A painting reflects this fraction of its linearised sRGB colour (cpp/gallery/gallery.h).
PAINTING_REFLECTANCE = 0.9


def _srgb_to_linear(c: np.ndarray) -> np.ndarray:
    c = np.asarray(c, np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def painting_albedo(rgb8: np.ndarray) -> np.ndarray:
    """The albedo the gallery gives a painting's sRGB8 texels (float32, same shape)."""
    return (PAINTING_REFLECTANCE * _srgb_to_linear(np.asarray(rgb8) / 255.0)).astype(np.float32)


def _vec3(value, what: str) -> tuple[float, float, float]:
    try:
        a = np.asarray(value, np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be 3 numbers, got {value!r}") from None
    if a.shape != (3,):
        raise ValueError(f"{what} must be 3 numbers, got {value!r}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{what} is not finite: {tuple(a)}")
    return (float(a[0]), float(a[1]), float(a[2]))


def _check_surface(s: Surface) -> tuple[np.ndarray, np.ndarray, tuple, tuple]:
    if not isinstance(s, Surface):
        raise ValueError(f"a room surface must be a Surface, got {type(s).__name__}")
    v = np.asarray(s.vertices, np.float64)
    if v.ndim != 2 or v.shape[1] != 3 or len(v) == 0:
        raise ValueError(f"surface {s.name!r}: vertices must have shape (n, 3), got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"surface {s.name!r}: a vertex is not finite (NaN or Inf)")
    if np.abs(v).max() > 1e15:
        raise ValueError(f"surface {s.name!r}: coordinates beyond 1e15 m")
    t = np.asarray(s.triangles)
    if t.ndim != 2 or t.shape[1] != 3 or len(t) == 0 or not np.issubdtype(t.dtype, np.integer):
        raise ValueError(f"surface {s.name!r}: triangles must be integers of shape (m, 3)")
    if t.min() < 0 or t.max() >= len(v):
        raise ValueError(f"surface {s.name!r}: a triangle indexes a vertex outside [0, {len(v)})")
    albedo = _vec3(s.albedo, f"surface {s.name!r}: albedo")
    if min(albedo) < 0 or max(albedo) >= 1:
        raise ValueError(f"surface {s.name!r}: albedo must be in [0, 1) per channel, got {albedo} "
                         "(a surface reflecting all light makes the light transport diverge)")
    emission = _vec3(s.emission, f"surface {s.name!r}: emission")
    if min(emission) < 0:
        raise ValueError(f"surface {s.name!r}: emission must be >= 0, got {emission}")
    return v, t.astype(np.int64), albedo, emission


def _painting_index(pack: TilePack, which) -> int:
    names = [p.name for p in pack.paintings]
    if isinstance(which, (bool, np.bool_)):
        raise ValueError(f"painting must be a name or an index, got {which!r}")
    if isinstance(which, (int, np.integer)):
        if not 0 <= int(which) < len(names):
            raise ValueError(f"painting index {int(which)} is not in the pack ({len(names)} paintings)")
        return int(which)
    if isinstance(which, str):
        if which not in names:
            raise ValueError(f"painting {which!r} is not in the pack (it holds {names})")
        return names.index(which)
    raise ValueError(f"painting must be a name or an index, got {which!r}")


def _check_slot(slot: PaintingSlot) -> tuple:
    if not isinstance(slot, PaintingSlot):
        raise ValueError(f"a painting slot must be a PaintingSlot, got {type(slot).__name__}")
    origin = _vec3(slot.origin, f"painting slot {slot.name!r}: origin")
    u = np.array(_vec3(slot.u_axis, f"painting slot {slot.name!r}: u_axis"))
    v = np.array(_vec3(slot.v_axis, f"painting slot {slot.name!r}: v_axis"))
    for what, x in (("width_m", slot.width_m), ("height_m", slot.height_m)):
        if isinstance(x, bool) or not isinstance(x, (int, float, np.floating, np.integer)) \
                or not math.isfinite(x) or x <= 0:
            raise ValueError(f"painting slot {slot.name!r}: {what} must be a positive finite number, got {x!r}")
    if abs(np.linalg.norm(u) - 1) > 1e-6 or abs(np.linalg.norm(v) - 1) > 1e-6 or abs(u @ v) > 1e-6:
        raise ValueError(f"painting slot {slot.name!r}: u_axis and v_axis must be orthonormal")
    return origin, tuple(u), tuple(v), float(slot.width_m), float(slot.height_m)


class Gallery(_core._Gallery):
    """A room (`RoomSpec`) with its painting slots bound to the paintings of a pack, as one
    Embree scene. Build it with :meth:`from_room`."""

    def __init__(self):
        super().__init__()
        self.spec: RoomSpec | None = None
        self.pack: TilePack | None = None
        self.slot_paintings: list[int] = []

    @classmethod
    def from_room(cls, spec: RoomSpec, pack) -> "Gallery":
        """The gallery of `spec` with each painting slot bound (by name or index) to a painting
        of `pack` (an open TilePack or its path). ValueError for a painting not in the pack,
        a room with no light, an albedo outside [0, 1), NaN coordinates, bad slot axes."""
        if not isinstance(spec, RoomSpec):
            raise ValueError(f"from_room takes a RoomSpec, got {type(spec).__name__}")
        if isinstance(pack, (str, os.PathLike)):
            pack = TilePack(Path(pack))
        if not isinstance(pack, TilePack):
            raise ValueError(f"pack must be a TilePack or a path, got {type(pack).__name__}")
        surfaces = [_check_surface(s) for s in spec.surfaces]
        if not any(max(e) > 0 for *_, e in surfaces):
            raise ValueError(f"room {spec.name!r} has no light: no surface has emission > 0")
        slots = [(_painting_index(pack, s.painting), _check_slot(s)) for s in spec.paintings]
        g = cls()
        for v, t, albedo, emission in surfaces:
            g._add_surface(np.ascontiguousarray(v, np.float32), np.ascontiguousarray(t), albedo, emission)
        for index, (origin, u, v, w, h) in slots:
            g._add_painting(pack, index, origin, u, v, w, h)
        g._commit()
        g.spec, g.pack, g.slot_paintings = spec, pack, [i for i, _ in slots]
        return g

    # lighting ---------------------------------------------------------------------------------

    def light(self, vt, photons: int = 1 << 19, radius: float | None = None, light_samples: int = 16,
              seed: int = 0, threads: int = 0, disc: bool = False, indirect: bool = True) -> dict:
        """The photon pass over the whole room and its photon map (replaces any previous
        lighting and bake). `radius` None: about 100 photons per gather disc. disc=True gathers
        over the surface disc (no darkening at room edges and painting borders; slower near
        other surfaces) instead of the sphere. light_samples: emitter samples per pixel of
        lighting "full". indirect=False: direct light only, no photon pass (no
        photons traced, the gather zero). Returns `stats`."""
        for name, value in (("photons", photons), ("light_samples", light_samples), ("seed", seed),
                            ("threads", threads)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
                raise ValueError(f"{name} must be a non-negative integer, got {value!r}")
        if not isinstance(indirect, (bool, np.bool_)):
            raise ValueError(f"indirect must be True or False, got {indirect!r}")
        r = 0.0 if radius is None else positive_float32(radius, "radius")  # 0: automatic
        self._light(vt, int(photons), r, int(light_samples), int(seed), int(threads), bool(disc),
                    bool(indirect))
        return self.stats

    def bake(self, spacing: float | None = None, light_samples: int = 16, threads: int = 0,
             progress: bool = False, stratified: bool = True, skip_unlit: bool = True,
             gather_stride: int = 2, inset_edges: bool = True, coarse_disc: bool = False,
             analytic_direct: bool = True, shadow_probes: int = 4, fill_covered: bool = True,
             indirect_filter: float = 0.0, final_gather: int = 36, sparse_final_gather: bool = True,
             hot_spots: float = 8.0) -> dict:
        """Bakes irradiance once for the current lighting: a lattice on every triangle, both
        sides, `spacing` metres apart along its edges (None: the room's diagonal / 200), each
        point with `light_samples` emitter samples plus the photon gather. stratified: the
        emitter samples come from a randomly shifted low-discrepancy lattice (unbiased, less
        noise; False: independent samples, lighting "full"'s estimator). skip_unlit: a side
        that no emitter faces and no photon reaches is zero without being computed (its
        stats["bake_sides_skipped"]). gather_stride=s (1, 2, 4, 8): photon gathers on every
        s-th lattice point only (1 / s^2 of them), interpolated between (default 2). inset_edges: the
        lattice points on a triangle's edges are computed a sixteenth of the spacing inside it
        (where surfaces meet, the point on the edge also lies on the neighbour's plane: shadow
        rays and the disc's clipping rays graze it); False: on the edge. coarse_disc (with
        light(disc=True)): the bake's discs clipped with at most 32 rays instead of 128 (about
        half the bake's time, a little more error). analytic_direct (with stratified): the
        emitters' exact unoccluded irradiance (Lambert's polygon formula) times the visible
        fraction of the samples' contribution (Heitz et al. 2018's ratio estimator): no noise
        where a point sees all of the light or none of it; False: the samples' plain mean.
        shadow_probes (with analytic_direct): that many samples' shadow rays first; when they
        all agree (all lit or all shadowed) the point's other samples are skipped (0: never).
        fill_covered: lattice points covered by a nearby surface (under a painting on a table,
        behind one on a wall: nine probe rays all blocked within half the spacing) are filled
        from their uncovered neighbours instead of computed, so that interpolation does not
        spread their darkness a lattice cell beyond the painting's edge
        (stats["bake_points_covered"]). indirect_filter: the photon gathers' part (indirect
        light; the direct light is left sharp) smoothed over each triangle's lattice by a local
        linear fit with Gaussian weights of this many gather radii (0: off): the photon map's
        density noise, frozen into cloud-like patches, averaged down (measured: it lowers the
        paintings' mottle but spreads the sphere gather's darkening at the room's edges, so it
        is off by default). final_gather=k: the indirect light as a final gather (Jensen) of k
        cosine rays per lattice point looking up a first pass's lattice (0: the photon density
        at the point). sparse_final_gather (with gather_stride s > 1): the final gather too on
        every s-th point only, interpolated between (the indirect light is smooth). The
        defaults, 36 rays on every other point each way, are the quality knob's `final`
        (gallery/quality.py): mottle below 1% on walls and floors and 0.5% on paintings in the
        measured rooms, light + bake about 1.5x the bake without a final gather. hot_spots=h (with
        final_gather): first-pass lattice points whose outgoing light (albedo x E) is above h
        times the room's mean (the ceiling a few centimetres from a light) leave the gather and
        light every point as small area lights with a shadow ray each: a few rays landing on such
        a patch would otherwise leave white specks all over the bake (0: off;
        stats["bake_hot_points"] counts them). progress=True shows a tqdm bar over the lattice
        rows. Returns `stats`."""
        s = 0.0 if spacing is None else float(spacing)
        if not math.isfinite(s) or s < 0 or (spacing is not None and s == 0):
            raise ValueError(f"spacing must be positive and finite, got {spacing!r}")
        if isinstance(light_samples, bool) or not isinstance(light_samples, (int, np.integer)):
            raise ValueError(f"light_samples must be an integer, got {light_samples!r}")
        if isinstance(gather_stride, bool) or gather_stride not in (1, 2, 4, 8):
            raise ValueError(f"gather_stride must be 1, 2, 4 or 8, got {gather_stride!r}")
        for name, value in (("inset_edges", inset_edges), ("coarse_disc", coarse_disc),
                            ("analytic_direct", analytic_direct), ("fill_covered", fill_covered),
                            ("sparse_final_gather", sparse_final_gather)):
            if not isinstance(value, (bool, np.bool_)):
                raise ValueError(f"{name} must be True or False, got {value!r}")
        if isinstance(shadow_probes, bool) or not isinstance(shadow_probes, (int, np.integer)) \
                or not 0 <= shadow_probes <= 1 << 16:
            raise ValueError(f"shadow_probes must be an integer in [0, 65536], got {shadow_probes!r}")
        f = float(indirect_filter) if isinstance(indirect_filter, (int, float, np.integer, np.floating)) \
            and not isinstance(indirect_filter, bool) else math.nan
        if not (math.isfinite(f) and 0 <= f <= 16):
            raise ValueError(f"indirect_filter must be a number in [0, 16] (gather radii), got {indirect_filter!r}")
        if isinstance(final_gather, bool) or not isinstance(final_gather, (int, np.integer)) \
                or not 0 <= final_gather <= 4096:
            raise ValueError(f"final_gather must be an integer in [0, 4096] (rays), got {final_gather!r}")
        h = float(hot_spots) if isinstance(hot_spots, (int, float, np.integer, np.floating)) \
            and not isinstance(hot_spots, bool) else math.nan
        if not (math.isfinite(h) and (h == 0 or 1 <= h <= 1e6)):
            raise ValueError(f"hot_spots must be 0 (off) or a number in [1, 1e6], got {hot_spots!r}")
        args = (s, int(light_samples), int(threads), bool(stratified), bool(skip_unlit),
                int(gather_stride), bool(inset_edges), bool(coarse_disc), bool(analytic_direct),
                int(shadow_probes), bool(fill_covered), f, int(final_gather), bool(sparse_final_gather), h)
        if not progress:
            self._bake(*args)
            return self.stats
        import threading

        from tqdm import tqdm

        failed = []

        def work():
            try:
                self._bake(*args)
            except BaseException as e:  # re-raised on the calling thread
                failed.append(e)

        worker = threading.Thread(target=work, name="gallery-bake")
        worker.start()
        with tqdm(desc="bake", unit="row", leave=False) as bar:
            while worker.is_alive():
                worker.join(0.2)
                done, total = self._bake_progress()
                bar.total, bar.n = total, done
                bar.refresh()
        if failed:
            raise failed[0]
        return self.stats

    # rendering --------------------------------------------------------------------------------

    def render_display(self, camera: Camera, vt, lighting: str = "baked", out: np.ndarray | None = None,
                       hits: bool = False, threads: int = 0, reference: bool = False):
        """The display pass at the camera's full resolution, one primary ray per pixel centre:
        (H, W, 3) float32 linear radiance (written into `out` when given). A painting's albedo
        is the VT's trilinear sample at the pixel's lambda; lighting "baked" and "full" light()
        (and bake()) with their defaults first if that has not been done. hits=True returns
        (rgb, dict) with per-pixel 'position' (H, W, 3) float32 (NaN where nothing is hit),
        'slot' (H, W) int32 (-1 off paintings), 'uv' (H, W, 2) float64 and 'lod' (H, W) float32
        (NaN off paintings), and 'irradiance' (H, W, 3) float32, the E of radiance = albedo x
        E / pi + emission (view-independent: another eye seeing the same point can reuse it).
        Baked without hits runs the walk's packet display pass (faster, equal to float
        rounding); reference=True (and hits=True) runs the per-pixel path, its oracle."""
        if lighting not in LIGHTING_MODES:
            raise ValueError(f"lighting must be one of {LIGHTING_MODES}, got {lighting!r}")
        if not isinstance(camera, Camera):
            raise ValueError(f"camera must be a gigascroll.Camera, got {type(camera).__name__}")
        if lighting != "unlit" and not self.lit:
            self.light(vt)
        if lighting == "baked" and not self.baked:
            self.bake()
        shape = (camera.height, camera.width, 3)
        if out is None:
            out = np.empty(shape, np.float32)
        elif not (isinstance(out, np.ndarray) and out.dtype == np.float32 and out.shape == shape
                  and out.flags.c_contiguous and out.flags.writeable):
            raise ValueError(f"out must be a writeable C-contiguous float32 array of shape {shape}")
        if not isinstance(reference, (bool, np.bool_)):
            raise ValueError(f"reference must be True or False, got {reference!r}")
        d = self._render_display(camera, vt, lighting, out, bool(hits), int(threads), bool(reference))
        return (out, dict(d)) if hits else out

    def stream(self, camera: Camera, vt, rounds: int = 3) -> int:
        """Makes the tiles this view reads resident: the feedback pass at the camera's full
        resolution, then each missing tile read from the pack and inserted (synchronously, for
        stills; the frame loop streams asynchronously): the requested tiles and their parents
        one level coarser, which trilinear filtering also reads (as the walk loads them;
        without them a pixel blended its level with a coarser pinned one, tile by tile).
        Repeats while new tiles are missing (at most `rounds` times). Returns the number of
        tiles inserted."""
        from .._core import NO_REQUEST, unpack_requests
        from .tile_keys import parent_keys

        levels = np.array([p.levels for p in self.pack.paintings], np.int64)
        inserted = 0
        for _ in range(int(rounds)):
            keys = self.render_view(camera, width=camera.width, height=camera.height)["keys"]
            keys = np.unique(keys[keys != NO_REQUEST])
            # parents first: the LRU keeps the finer tiles should a small cache overflow
            keys = np.concatenate([parent_keys(keys, levels), keys])
            missing = vt.request(keys) if len(keys) else keys
            if len(missing) == 0:
                break
            for p, l, x, y in zip(*unpack_requests(missing)):
                vt.insert((int(p), int(l), int(x), int(y)), self.pack.read_tile(int(p), int(l), int(x), int(y)))
                inserted += 1
        return inserted

    def still(self, camera: Camera, lighting: str = "baked", vt=None, slots: int | None = None,
              progress: bool = False, spp: int = 1, **light_options) -> np.ndarray:
        """A still frame: a virtual texture sized for the view (`slots` x `slots` tiles, default
        from the view's requests), the view's tiles streamed in (`stream`), lighting as needed,
        then `render_display`. light_options go to `light` when it has not run (light_samples
        to `bake` too).

        spp = k^2 (1, 4, 9, 16, ...): k x k camera samples per pixel on a stratified sub-pixel
        grid, averaged in linear radiance (box filter): the still rendered at k times the
        resolution (each sample's texture level for its own footprint, and in lighting "full"
        its own emitter samples) and each k x k block averaged."""
        if isinstance(spp, bool) or not isinstance(spp, (int, np.integer)) or spp < 1 \
                or math.isqrt(int(spp)) ** 2 != spp:
            raise ValueError(f"spp must be a square (1, 4, 9, 16, ...): k x k samples per pixel, "
                             f"got {spp!r}")
        k = math.isqrt(int(spp))
        if k > 1:
            fine = Camera(list(camera.position), list(np.add(camera.position, camera.forward)),
                          list(camera.up), float(camera.fov),
                          resolution=(k * camera.width, k * camera.height))
            image = self.still(fine, lighting, vt, slots, progress, **light_options)
            h, w = camera.height, camera.width
            return image.reshape(h, k, w, k, 3).mean(axis=(1, 3), dtype=np.float64).astype(np.float32)
        from .. import runtime

        if vt is None:
            from .._core import NO_REQUEST

            keys = self.render_view(camera, width=camera.width, height=camera.height)["keys"]
            wanted = len(np.unique(keys[keys != NO_REQUEST]))
            side = slots or min(64, max(8, math.ceil(math.sqrt(2 * wanted + 64 * max(1, len(self.slot_paintings))))))
            vt = runtime.VirtualTexture(self.pack, (side, side))
        self.stream(camera, vt)
        if lighting != "unlit" and not self.lit:
            self.light(vt, **light_options)
        if lighting == "baked" and not self.baked:
            samples = light_options.get("light_samples")
            self.bake(progress=progress, **({} if samples is None else {"light_samples": samples}))
        return self.render_display(camera, vt, lighting=lighting)

    def render_still(self, camera: Camera, lighting: str = "baked", return_stats: bool = False, *,
                     photons: int = 1 << 18, radius=None, grid: str = "adaptive",
                     gather: str = "radius", spp: int = 1, seed: int = 0, kernel: str = "box",
                     light_samples=None, pipeline: str = "fused", cooperative: bool = False,
                     direct: bool = True, indirect: bool = True, threads: int = 0,
                     progressive: bool = False, snapshots=(), final_gather: bool = False,
                     disc=None):
        """`gigascroll.render(gallery, camera, ...)`: the still (`still`) with the photon
        renderer's options that a gallery has (photons, radius, seed, threads, indirect, disc
        and light_samples for its photon pass and bake; spp, a square k^2, supersamples);
        the options it does not have (progressive, another grid, gather, kernel or pipeline,
        direct=False) raise ValueError rather than being ignored."""
        lacks = {"progressive": progressive, "snapshots": bool(snapshots), "final_gather": final_gather,
                 "grid": grid != "adaptive", "gather": gather != "radius", "kernel": kernel != "box",
                 "pipeline": pipeline != "fused", "cooperative": cooperative, "direct": not direct}
        given = [name for name, on in lacks.items() if on]
        if given:
            raise ValueError(f"{', '.join(given)}: a Gallery's still does not have "
                             f"{'this option' if len(given) == 1 else 'these options'} (the "
                             "gallery's gather is a box radius gather on the adaptive grid, "
                             "one pass, direct light always)")
        options = {"radius": radius, "disc": disc, "light_samples": light_samples}
        image = self.still(camera, lighting=lighting, spp=spp, photons=photons, seed=seed,
                           threads=threads, indirect=indirect,
                           **{k: v for k, v in options.items() if v is not None})
        return (image, dict(self.stats)) if return_stats else image

    def camera(self, resolution=(256, 256), fov: float = 60.0, eye=None, target=None) -> Camera:
        """A camera at the room's suggested eye and target (or the given ones), y up."""
        spec = self.spec
        eye = eye if eye is not None else (spec.camera_eye if spec and spec.camera_eye else None)
        target = target if target is not None else (spec.camera_target if spec and spec.camera_target else None)
        if eye is None or target is None:
            # No suggestion: from the middle of the room at eye height (1.6 m, or 55% of a
            # lower room) toward the first painting, else along -z.
            lo, hi = (np.array(b, np.float64) for b in self.bounds)
            c = (lo + hi) / 2
            c[1] = lo[1] + min(1.6, 0.55 * (hi[1] - lo[1]))
            eye = eye if eye is not None else tuple(c)
            if target is None:
                if spec and spec.paintings:
                    s0 = spec.paintings[0]
                    target = tuple(np.array(s0.origin, float) + 0.5 * s0.width_m * np.array(s0.u_axis, float)
                                   + 0.5 * s0.height_m * np.array(s0.v_axis, float))
                else:
                    target = tuple(np.array(eye, float) + np.array([0.0, 0.0, -1.0]))
        return Camera(list(_vec3(eye, "eye")), list(_vec3(target, "target")), [0, 1, 0], float(fov),
                      resolution=(int(resolution[0]), int(resolution[1])))

    # the same room for Mitsuba 3 --------------------------------------------------------------

    def mitsuba_level(self, slot: int, max_width: int = 2048) -> int:
        """The mip level of a slot's painting written to Mitsuba: the finest whose width is at
        most max_width texels. ValueError for a slot outside [0, slots) or a width below 1."""
        n = len(self.slot_paintings)
        if not isinstance(slot, (int, np.integer)) or isinstance(slot, bool) or not 0 <= slot < n:
            raise ValueError(f"slot must be an integer in [0, {n - 1}] (the room's {n} painting "
                             f"slots), got {slot!r}" if n else f"the room has no painting slots "
                             f"(slot {slot!r})")
        if not isinstance(max_width, (int, np.integer)) or isinstance(max_width, bool) or max_width < 1:
            raise ValueError(f"max_width must be a positive integer, got {max_width!r}")
        p = self.pack.paintings[self.slot_paintings[slot]]
        for level, (w, _) in enumerate(p.level_sizes):
            if w <= max_width:
                return level
        return p.levels - 1

    def to_mitsuba_dict(self, camera: Camera, levels: dict | int | None = None, max_depth: int = -1,
                        integrator: dict | None = None) -> dict:
        """The same room for `mitsuba.load_dict`: each surface a mesh with a twosided diffuse
        BSDF (and an area emitter where it emits, one-sided along its winding normal like
        ours), each painting a two-triangle mesh with its uv and a bilinear `bitmap` texture of
        one mip level read from the pack (`levels`: one level for all, {slot: level}, or None
        for `mitsuba_level`), converted to albedo exactly as the gallery converts texels; the
        sensor is our camera (perspective, fov_axis 'y', box filter)."""
        import mitsuba as mi

        if mi.variant() is None:
            mi.set_variant("scalar_rgb")
        from ..pack import read_level

        def mesh(name, v, f, uv=None, bsdf=None, emitter=None):
            props = mi.Properties()
            props["bsdf"] = mi.load_dict(bsdf)
            if emitter is not None:
                props["emitter"] = mi.load_dict(emitter)
            m = mi.Mesh(name, len(v), len(f), props=props, has_vertex_texcoords=uv is not None)
            p = mi.traverse(m)
            p["vertex_positions"] = np.asarray(v, np.float32).ravel()
            p["faces"] = np.asarray(f, np.uint32).ravel()
            if uv is not None:
                p["vertex_texcoords"] = np.asarray(uv, np.float32).ravel()
            p.update()
            return m

        eye = np.array(camera.position)
        d = {"type": "scene",
             "integrator": integrator or {"type": "path", "max_depth": int(max_depth)},
             "sensor": {"type": "perspective", "fov_axis": "y", "fov": float(camera.fov),
                        "to_world": mi.ScalarTransform4f().look_at(
                            origin=eye.tolist(), target=(eye + np.array(camera.forward)).tolist(),
                            up=list(camera.up)),
                        "film": {"type": "hdrfilm", "width": int(camera.width), "height": int(camera.height),
                                 "rfilter": {"type": "box"}, "pixel_format": "rgb"},
                        "sampler": {"type": "independent"}}}
        for i, s in enumerate(self.spec.surfaces):
            v, t, albedo, emission = _check_surface(s)
            bsdf = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(albedo)}}}
            emitter = ({"type": "area", "radiance": {"type": "rgb", "value": list(emission)}}
                       if max(emission) > 0 else None)
            d[f"surface{i:03d}"] = mesh(f"surface{i:03d}", v, t, bsdf=bsdf, emitter=emitter)
        for i, slot in enumerate(self.spec.paintings):
            origin, u, v, w, h = _check_slot(slot)
            o, u, v = np.array(origin), np.array(u), np.array(v)
            level = (levels.get(i) if isinstance(levels, dict) else levels)
            if level is None:
                level = self.mitsuba_level(i)
            image = painting_albedo(read_level(self.pack, self.slot_paintings[i], int(level)))
            tex = {"type": "bitmap", "bitmap": mi.Bitmap(np.ascontiguousarray(image)), "raw": True,
                   "filter_type": "bilinear", "wrap_mode": "clamp"}
            verts = [o, o + w * u, o + w * u + h * v, o + h * v]
            d[f"painting{i:03d}"] = mesh(f"painting{i:03d}", verts, [(0, 1, 2), (0, 2, 3)],
                                         uv=[(0, 0), (1, 0), (1, 1), (0, 1)],
                                         bsdf={"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": tex}})
        return d

