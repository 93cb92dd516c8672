"""Photon mapping on Embree (VR-photon-mapping): scenes, cameras, photon maps and the renderer.

    scene, camera = gigascroll.builtin_scene("cornell", resolution=(128, 128))
    image = gigascroll.render(scene, camera, photons=512**2, radius=0.02)  # (H, W, 3) float32

Everything is Lambertian. Radiance is linear; `save_image` writes EXR (float) or PNG
(sRGB-encoded, clipped). Data flows one way: build a Scene, commit it, render it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from . import _core
from ._core import Camera, PhotonMap, StereoCamera
from .errors import expect_type, positive_float32

__all__ = ["Scene", "StereoCamera", "PhotonMap", "builtin_scene", "BUILTIN_SCENES",
           "RoomScene", "room_scene", "ROOMS", "default_radius", "render", "render_stereo",
           "trace_photons", "save_image", "relmse"]

# The test rooms built from rectangles (see RoomScene); Mitsuba can render each of them.
ROOMS = ("room_lit", "room_indirect", "room_partition")

# name -> the scene's size scale: VR-photon-mapping's radii (0.02-0.2, a Cornell box about 2 units
# wide) are multiplied by it.
BUILTIN_SCENES = {"cornell": 1.0, "office": 4.0, "furnace": 1.0, **{name: 2.0 for name in ROOMS}}


class Scene(_core._Scene):
    """Lambertian triangle meshes in an Embree BVH; emissive triangles are area lights.

    Call `add_mesh` (or `add_mesh_file`) for each mesh, then `commit()` before rendering.
    """

    def add_mesh(self, vertices, triangles, albedo=(0.5, 0.5, 0.5), emission=(0.0, 0.0, 0.0)) -> int:
        """Add a mesh. vertices (N, 3) float, triangles (M, 3) int, albedo (3,) or (M, 3) in [0, 1),
        emission (3,) radiance emitted toward the side of counter-clockwise winding (default 0).

        A surface may both reflect and emit. Degenerate triangles are dropped (returns the number
        kept); NaN/Inf vertices, out-of-range indices and albedo outside [0, 1) raise ValueError.
        """
        v = _float_array(vertices, "vertices")
        t = np.asarray(triangles)
        if t.dtype.kind not in "iu":
            raise ValueError(f"add_mesh: triangles must be integers, got dtype {t.dtype}")
        if t.size and (t.max() > np.iinfo(np.int64).max or t.min() < np.iinfo(np.int64).min):
            raise ValueError("add_mesh: triangle indices out of range")
        t = np.ascontiguousarray(t, dtype=np.int64)
        a = _float_array(albedo, "albedo")
        e = _float_array(emission, "emission")
        if e.shape != (3,):
            raise ValueError(f"add_mesh: emission must have shape (3,), got {e.shape}")
        if v.ndim != 2 or v.shape[1] != 3:
            raise ValueError(f"add_mesh: vertices must have shape (N, 3), got {v.shape}")
        if t.ndim != 2 or t.shape[1] != 3:
            raise ValueError(f"add_mesh: triangles must have shape (M, 3), got {t.shape}")
        return self._add_mesh(v, t, a, tuple(float(x) for x in e))

    def add_mesh_file(self, path, albedo=(0.5, 0.5, 0.5), emission=(0.0, 0.0, 0.0), transform=None) -> int:
        """Load an OBJ/PLY/... mesh with trimesh and add it (optionally under a 4x4 transform)."""
        import trimesh

        path = Path(path)
        if not path.is_file():
            raise OSError(f"mesh file not found: {path}")
        try:
            mesh = trimesh.load(path, force="mesh", process=False)
        except Exception as e:  # trimesh raises many types on bad files
            raise OSError(f"cannot read mesh {path}: {e}") from e
        if len(mesh.faces) == 0:
            raise ValueError(f"mesh {path} has no triangles")
        v = np.asarray(mesh.vertices, dtype=np.float64)
        if transform is not None:
            m = np.asarray(transform, dtype=np.float64)
            if m.shape != (4, 4):
                raise ValueError("transform must be a 4x4 matrix")
            v = v @ m[:3, :3].T + m[:3, 3]
        return self.add_mesh(v, np.asarray(mesh.faces), albedo, emission)


def _float_array(x, name: str) -> np.ndarray:
    a = np.asarray(x)
    if a.dtype.kind not in "fiu":
        raise ValueError(f"{name} must be numeric, got dtype {a.dtype}")
    return np.ascontiguousarray(a, dtype=np.float32)


def builtin_scene(name: str, resolution: Sequence[int] | None = None, albedo: float = 0.5,
                  emission: float = 1.0) -> tuple[Scene, Camera]:
    """A committed built-in scene and its camera: 'cornell' (Mitsuba 3's cornell_box()),
    'office' (~710k triangles), 'furnace' (closed sphere, uniform albedo and emission) or one of
    ROOMS (see room_scene)."""
    if name not in BUILTIN_SCENES:
        raise ValueError(f"unknown scene {name!r}; built-in scenes: {', '.join(BUILTIN_SCENES)}")
    if name == "furnace" and not (0.0 <= albedo < 1.0):
        raise ValueError("furnace: albedo must be in [0, 1)")
    w, h = resolution if resolution is not None else ((64, 64) if name == "furnace" else (256, 256))
    if name in ROOMS:
        return room_scene(name).build(resolution=(w, h))
    scene = Scene()
    camera = _core._build_scene(name, scene, int(w), int(h), float(albedo), float(emission))
    scene.commit()
    return scene, camera


@dataclass(frozen=True)
class _Rect:
    """A parallelogram c + s a + t b, s, t in [-1, 1]: Mitsuba's `rectangle` under the
    transform with columns (a, b, unit normal, c). Emits (one-sided) toward a x b."""
    c: tuple
    a: tuple
    b: tuple
    albedo: tuple
    emission: tuple = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class RoomScene:
    """A scene made of rectangles only, so that it is built identically here and in Mitsuba 3.

    `build()` gives the committed gigascroll Scene and Camera; `to_mitsuba_dict()` the same
    scene for `mitsuba.load_dict` (path tracer, perspective sensor with fov_axis 'y' like our
    camera, box pixel filter like our jittered pixels, every BSDF `twosided` because our
    surfaces reflect on both sides). `regions` names pixel masks used to measure bias."""
    name: str
    rects: tuple
    eye: tuple
    target: tuple
    fov: float

    def build(self, resolution=(64, 64)) -> tuple[Scene, Camera]:
        scene = Scene()
        for r in self.rects:
            c, a, b = (np.array(x, np.float64) for x in (r.c, r.a, r.b))
            v = np.array([c - a - b, c + a - b, c + a + b, c - a + b])
            scene.add_mesh(v, [[0, 1, 2], [2, 3, 0]], r.albedo, r.emission)
        scene.commit()
        w, h = resolution
        return scene, Camera(list(self.eye), list(self.target), [0, 1, 0], self.fov, resolution=(int(w), int(h)))

    def to_mitsuba_dict(self, resolution=(64, 64), integrator: dict | None = None) -> dict:
        import mitsuba as mi

        if mi.variant() is None:
            mi.set_variant("scalar_rgb")
        w, h = resolution
        d = {"type": "scene",
             "integrator": integrator or {"type": "path", "max_depth": -1},
             "sensor": {"type": "perspective", "fov_axis": "y", "fov": float(self.fov),
                        "to_world": mi.ScalarTransform4f().look_at(origin=list(self.eye), target=list(self.target),
                                                                   up=[0, 1, 0]),
                        "film": {"type": "hdrfilm", "width": int(w), "height": int(h),
                                 "rfilter": {"type": "box"}, "pixel_format": "rgb"},
                        "sampler": {"type": "independent"}}}
        for i, r in enumerate(self.rects):
            a, b = np.array(r.a, float), np.array(r.b, float)
            n = np.cross(a, b)
            n /= np.linalg.norm(n)
            m = np.eye(4)
            m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = a, b, n, r.c
            shape = {"type": "rectangle", "to_world": mi.ScalarTransform4f(m.tolist()),
                     "bsdf": {"type": "twosided", "bsdf": {"type": "diffuse",
                                                           "reflectance": {"type": "rgb", "value": list(r.albedo)}}}}
            if any(e > 0 for e in r.emission):
                shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": list(r.emission)}}
            d[f"rect{i:03d}"] = shape
        return d


def _box(c, half, albedo) -> list[_Rect]:
    """An axis-aligned box as six outward-facing rectangles."""
    out = []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            u, w = np.zeros(3), np.zeros(3)
            u[(axis + 1) % 3], w[(axis + 2) % 3] = half[(axis + 1) % 3], half[(axis + 2) % 3]
            if sign < 0:
                u, w = w, u  # keep u x w pointing outward
            centre = np.array(c, float)
            centre[axis] += sign * half[axis]
            out.append(_Rect(tuple(centre), tuple(u), tuple(w), albedo))
    return out


def _room_shell(ceiling_light: bool) -> list[_Rect]:
    """A 4 m x 2.6 m x 4 m room, x and z in [-2, 2], y in [0, 2.6], surfaces facing inward."""
    wall, floor, ceiling = (0.75, 0.73, 0.70), (0.45, 0.42, 0.40), (0.80, 0.80, 0.80)
    rects = [
        _Rect((0, 0, 0), (0, 0, 2), (2, 0, 0), floor),              # floor, normal +y
        _Rect((0, 2.6, 0), (2, 0, 0), (0, 0, 2), ceiling),          # ceiling, normal -y
        _Rect((0, 1.3, -2), (2, 0, 0), (0, 1.3, 0), wall),          # back, normal +z
        _Rect((0, 1.3, 2), (0, 1.3, 0), (2, 0, 0), wall),           # front, normal -z
        _Rect((-2, 1.3, 0), (0, 1.3, 0), (0, 0, 2), wall),          # left, normal +x
        _Rect((2, 1.3, 0), (0, 0, 2), (0, 1.3, 0), wall),           # right, normal -x
    ]
    if ceiling_light:  # a 0.8 m square panel 1 cm below the ceiling, emitting downward
        rects.append(_Rect((0, 2.59, 0), (0.4, 0, 0), (0, 0, 0.4), (0.0, 0.0, 0.0), (10.0, 10.0, 10.0)))
    return rects


def room_scene(name: str) -> RoomScene:
    """The three rooms the photon mapper's accuracy is tested on (against Mitsuba):
    - room_lit: a ceiling panel lights the room directly; a strongly red painting (1 cm thick)
      hangs 2 cm in front of the back wall, a white cube stands on the floor;
    - room_indirect: the panel hangs 30 cm below the ceiling and emits upward: every surface
      but the ceiling is lit indirectly;
    - room_partition: a 2 cm partition at x = 0 splits the room, with a full-height slit
      30 cm wide; the light is on the far side, the camera on the dark side looks at the partition's
      foot, where a sphere gather leaks light along the coplanar floor."""
    if name == "room_lit":
        rects = _room_shell(True) + _box((0, 1.4, -1.975), (0.6, 0.4, 0.005), (0.80, 0.06, 0.04))
        rects += _box((0.9, 0.25, -0.9), (0.25, 0.25, 0.25), (0.75, 0.75, 0.75))
        return RoomScene(name, tuple(rects), (0.0, 1.3, 1.9), (0.0, 1.1, -2.0), 60.0)
    if name == "room_indirect":
        rects = _room_shell(False)
        rects.append(_Rect((0, 1.9, 0), (0, 0, 0.5), (0.5, 0, 0), (0.0, 0.0, 0.0), (10.0, 10.0, 10.0)))  # emits +y
        rects += _box((0.9, 0.25, -0.9), (0.25, 0.25, 0.25), (0.75, 0.75, 0.75))
        return RoomScene(name, tuple(rects), (0.0, 1.3, 1.9), (0.0, 1.0, -2.0), 60.0)
    if name == "room_partition":
        rects = [r for r in _room_shell(False)]
        rects.append(_Rect((-1.0, 2.59, 0), (0.4, 0, 0), (0, 0, 0.4), (0.0, 0.0, 0.0), (20.0, 20.0, 20.0)))
        partition = (0.75, 0.73, 0.70)
        rects += _box((0, 1.3, -1.075), (0.01, 1.3, 0.925), partition)  # z in [-2, -0.15]
        rects += _box((0, 1.3, 1.075), (0.01, 1.3, 0.925), partition)   # z in [0.15, 2]
        return RoomScene(name, tuple(rects), (1.9, 1.3, 0.6), (0.0, 0.4, -0.2), 60.0)
    raise ValueError(f"unknown test room {name!r}; test rooms: {', '.join(ROOMS)}")


def default_radius(scene: Scene) -> float:
    """1% of the scene's bounding-box diagonal (0.035 in the Cornell box)."""
    expect_type(scene, _core._Scene, "scene")
    lo, hi = scene.bounds
    return 0.01 * math.dist(lo, hi)


def _settings(scene, photons, radius, grid, gather, k, kernel, spp, light_samples, seed, pipeline,
              cooperative, direct, indirect, threads, hash_mode, disc=False) -> dict:
    if not isinstance(scene, _core._Scene):
        raise TypeError(f"scene must be a gigascroll Scene (or, for render, a Gallery), not "
                        f"{type(scene).__name__}")
    if radius is None:
        radius = default_radius(scene)
    for name, value in (("photons", photons), ("k", k), ("spp", spp), ("light_samples", light_samples),
                        ("seed", seed), ("threads", threads)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
            raise ValueError(f"{name} must be an integer, got {value!r}")
        if value < 0:
            raise ValueError(f"{name} must be non-negative, got {value}")
        limit = 1 << 64 if name in ("photons", "seed") else 1 << 31
        if value >= limit:
            raise ValueError(f"{name} must be below 2^{limit.bit_length() - 1}, got {value}")
    radius = positive_float32(radius, "radius")
    if photons == 0 and indirect:
        raise ValueError("photons must be positive (or pass indirect=False)")
    return dict(photons=int(photons) if photons else 1, radius=radius, grid=grid, gather=gather, k=int(k),
                kernel=kernel, spp=int(spp), light_samples=int(light_samples), seed=int(seed),
                pipeline=pipeline, cooperative=bool(cooperative), direct=bool(direct),
                indirect=bool(indirect), threads=int(threads), hash_mode=hash_mode, disc=bool(disc))


def render(scene: Scene, camera: Camera, photons: int = 1 << 18, radius: float | None = None,
           grid: str = "adaptive", gather: str = "radius", k: int = 50, spp: int = 1, seed: int = 0,
           kernel: str = "box", light_samples: int | None = None, pipeline: str = "fused",
           cooperative: bool = False, direct: bool = True, indirect: bool = True, threads: int = 0,
           hash_mode: str = "auto", return_stats: bool = False, progressive: bool = False,
           passes: int = 16, time_budget: float | None = None, alpha: float = 2 / 3,
           snapshots: Sequence[int] = (), disc: bool | None = None, lighting: str = "baked",
           final_gather: bool = False, coarse_passes: int = 64):
    """Render linear radiance, float32 (H, W, 3).

    `scene` may be a `gigascroll.Gallery`: its still (`Gallery.still`) with `lighting`
    "baked", "full" or "unlit": photons, radius, seed, threads, indirect, disc and
    light_samples go to its photon pass (and bake), spp (a square k^2) supersamples the still;
    options the gallery does not have (progressive, another grid, gather, kernel or pipeline,
    direct=False) raise ValueError rather than being ignored.

    light_samples: emitter samples per shading point (None: 1 for a scene, stratified when
    more; the gallery's 16).

    Direct light by sampling the emitters with shadow rays; indirect light by density estimation
    in the photon map (grid 'adaptive': cells sized from the photon density and culled against the
    gather sphere, the fastest; 'hash': VR-photon-mapping's grid; or 'kdtree'; gather 'radius' with no heap, or 'knn' with a
    heap of k; kernel 'box' or 'cone'). pipeline 'fused' or 'two-pass'; cooperative=True (two-pass,
    grid='hash', radius gather) streams each photon once through a block of hit points in one cell.
    The same seed gives the same image for any thread count. return_stats=True also returns a
    dict of pass times (seconds) and counts.

    disc=True gathers over the surface disc instead of the sphere: photons within 0.1 r of the
    tangent plane only, the disc clipped per sector (16) by rays to where walls stand, the surface
    ends or something overhangs it (and shrunk next to an overhang), and divided by the clipped
    area (removes the darkening at edges and corners, the leak along a floor under a thin
    partition and a wall's light on a painting in front of it; costs up to 128 rays per gather
    where another surface is within r). Default (None): on wherever the options
    allow it (box kernel, radius gather, not cooperative), for one-shot and progressive renders.

    progressive=True: stochastic progressive photon mapping (consistent: converges to the exact
    image as passes grow). Each of `passes` passes (or fewer when `time_budget` seconds run out)
    takes one camera sample per pixel and `photons` new photons; `radius` is the initial radius,
    shrunk per pixel by the alpha rule. `snapshots` lists pass counts whose images are returned
    in stats['snapshots'] as (passes, seconds, image). final_gather=True (progressive only)
    gathers the photons where one diffuse bounce from the first hit lands, with that point's
    direct light, instead of at the first hit. The first `coarse_passes` passes clip the disc
    coarsely (8 sectors, up to 32 rays): a pass weighs 1 / passes in the image, so their larger
    edge bias fades while the first passes, at the largest radii, get cheap.
    """
    if isinstance(scene, _core._Gallery):  # a gigascroll.Gallery: its still (the gallery's rules)
        return scene.render_still(
            camera, lighting=lighting, return_stats=return_stats, photons=photons, radius=radius,
            grid=grid, gather=gather, spp=spp, seed=seed, kernel=kernel,
            light_samples=light_samples, pipeline=pipeline, cooperative=cooperative, direct=direct,
            indirect=indirect, threads=threads, progressive=progressive, snapshots=snapshots,
            final_gather=final_gather, disc=disc)
    if light_samples is None:
        light_samples = 1
    if disc is None:  # where the options allow it; otherwise their own error message comes first
        disc = kernel == "box" and gather == "radius" and not cooperative
    s = _settings(scene, photons, radius, grid, gather, k, kernel, spp, light_samples, seed, pipeline,
                  cooperative, direct, indirect, threads, hash_mode, disc)
    if not isinstance(final_gather, (bool, np.bool_)):
        raise ValueError(f"final_gather must be True or False, got {final_gather!r}")
    if not progressive:
        if snapshots:
            raise ValueError("snapshots need progressive=True")
        if final_gather:
            raise ValueError("final_gather needs progressive=True")
        image, stats = _core._render(scene, camera, **s)
        return (image, stats) if return_stats else image
    if isinstance(passes, bool) or not isinstance(passes, (int, np.integer)) or not 1 <= passes <= 1 << 24:
        raise ValueError(f"passes must be an integer in [1, 2^24], got {passes!r}")
    budget = 0.0 if time_budget is None else float(time_budget)
    if not math.isfinite(budget) or budget <= 0 and time_budget is not None:
        raise ValueError(f"time_budget must be positive and finite, got {time_budget!r}")
    alpha = positive_float32(alpha, "alpha")  # the core's float: 1e-46 would be 0 there
    if not alpha < 1:
        raise ValueError(f"alpha must be in (0, 1), got {alpha}")
    if isinstance(coarse_passes, bool) or not isinstance(coarse_passes, (int, np.integer)) or not 0 <= coarse_passes <= 1 << 24:
        raise ValueError(f"coarse_passes must be an integer in [0, 2^24], got {coarse_passes!r}")
    shots = [int(x) for x in snapshots]
    if any(x < 1 for x in shots):
        raise ValueError("snapshots must be positive pass counts")
    image, stats = _core._render_progressive(scene, camera, **s, passes=int(passes), time_budget=budget,
                                             alpha=alpha, snapshots=shots, final_gather=bool(final_gather),
                                             coarse_passes=int(coarse_passes))
    return (image, stats) if return_stats else image


def render_stereo(scene: Scene, eyes: StereoCamera, reuse: bool = True, photons: int = 1 << 18,
                  radius: float | None = None, grid: str = "adaptive", gather: str = "radius", k: int = 50,
                  spp: int = 1, seed: int = 0, kernel: str = "box", light_samples: int = 1,
                  direct: bool = True, indirect: bool = True, threads: int = 0):
    """Render both eyes: (left, right, stats). With reuse=True the left eye writes the colour of
    each hit point the right eye can see into the right image (VR-photon-mapping §3.3); stats has
    'reused_share' (fraction of right-eye pixels written that way) and pass times."""
    s = _settings(scene, photons, radius, grid, gather, k, kernel, spp, light_samples, seed, "fused",
                  False, direct, indirect, threads, "auto")
    return _core._render_stereo(scene, eyes, bool(reuse), **s)


def trace_photons(scene: Scene, count: int, seed: int = 0, threads: int = 0) -> dict:
    """The photon pass alone: dict of 'position', 'power', 'normal' (N, 3) float32 arrays of the
    stored photons, 'emitted' (count) and 'emitted_power' (RGB flux of all emitted photons)."""
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count <= 0:
        raise ValueError(f"count must be a positive integer, got {count!r}")
    return _core._trace_photons(scene, int(count), int(seed), int(threads))


def save_image(path, image: np.ndarray, display=None) -> None:
    """Write linear radiance as EXR/HDR (float, the radiance itself) or PNG/JPEG/TIFF (8-bit
    sRGB through `display`, a display_mapping.Display: exposure and tone curve; None: factor
    1, the neutral curve). Written by outputs.write_image: under a temporary name, closed with
    errors checked, then renamed, so a failed write (a full disk included) never leaves a
    complete-looking file."""
    from .display_mapping import Display
    from .outputs import write_image

    path = Path(path)
    img = np.asarray(image, dtype=np.float32)
    if img.ndim != 3 or img.shape[2] != 3:
        raise ValueError(f"image must have shape (H, W, 3), got {img.shape}")
    ext = path.suffix.lower()
    if ext in (".exr", ".hdr"):
        data = img
    elif ext in (".png", ".jpg", ".jpeg", ".tif", ".tiff"):
        data = (display or Display()).srgb8(img)
    else:
        raise ValueError(f"unsupported image format {ext!r} (use .exr, .hdr, .png, .jpg or .tif)")
    if not path.parent.is_dir():
        raise OSError(f"directory does not exist: {path.parent}")
    write_image(path, data, quality=95, durable=True)


def relmse(image: np.ndarray, reference: np.ndarray, eps: float = 1e-2) -> float:
    """Relative mean squared error, mean((x - ref)^2 / (ref^2 + eps)), over pixels and channels.
    eps keeps black pixels from dominating (the usual convention in rendering papers)."""
    image = np.asarray(image, dtype=np.float64)
    reference = np.asarray(reference, dtype=np.float64)
    if image.shape != reference.shape:
        raise ValueError(f"shape mismatch: {image.shape} vs {reference.shape}")
    return float(np.mean((image - reference) ** 2 / (reference ** 2 + eps)))
