"""Photon mapping on Embree (seed 001): scenes, cameras, photon maps and the renderer.

    scene, camera = gigascroll.builtin_scene("cornell", resolution=(128, 128))
    image = gigascroll.render(scene, camera, photons=512**2, radius=0.02)  # (H, W, 3) float32

Everything is Lambertian. Radiance is linear; `save_image` writes EXR (float) or PNG
(sRGB-encoded, clipped). Data flows one way: build a Scene, commit it, render it.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Sequence

import numpy as np

from . import _core
from ._core import Camera, PhotonMap, StereoCamera

__all__ = ["Scene", "Camera", "StereoCamera", "PhotonMap", "builtin_scene", "BUILTIN_SCENES",
           "default_radius", "render", "render_stereo", "trace_photons", "save_image", "relmse"]

# name -> the scene's size scale: seed 001's radii (0.02-0.2, a Cornell box about 2 units
# wide) are multiplied by it.
BUILTIN_SCENES = {"cornell": 1.0, "office": 4.0, "furnace": 1.0}


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
    'office' (~710k triangles) or 'furnace' (closed sphere, uniform albedo and emission)."""
    if name not in BUILTIN_SCENES:
        raise ValueError(f"unknown scene {name!r}; built-in scenes: {', '.join(BUILTIN_SCENES)}")
    if name == "furnace" and not (0.0 <= albedo < 1.0):
        raise ValueError("furnace: albedo must be in [0, 1)")
    w, h = resolution if resolution is not None else ((64, 64) if name == "furnace" else (256, 256))
    scene = Scene()
    camera = _core._build_scene(name, scene, int(w), int(h), float(albedo), float(emission))
    scene.commit()
    return scene, camera


def default_radius(scene: Scene) -> float:
    """1% of the scene's bounding-box diagonal (0.035 in the Cornell box)."""
    lo, hi = scene.bounds
    return 0.01 * math.dist(lo, hi)


def _settings(scene, photons, radius, grid, gather, k, kernel, spp, light_samples, seed, pipeline,
              cooperative, direct, indirect, threads, hash_mode) -> dict:
    if radius is None:
        radius = default_radius(scene)
    for name, value in (("photons", photons), ("k", k), ("spp", spp), ("light_samples", light_samples),
                        ("seed", seed), ("threads", threads)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
            raise ValueError(f"{name} must be an integer, got {value!r}")
        if value < 0:
            raise ValueError(f"{name} must be non-negative, got {value}")
    radius = float(radius)
    if not math.isfinite(radius) or radius <= 0:
        raise ValueError(f"radius must be positive and finite, got {radius}")
    if photons == 0 and indirect:
        raise ValueError("photons must be positive (or pass indirect=False)")
    return dict(photons=int(photons) if photons else 1, radius=radius, grid=grid, gather=gather, k=int(k),
                kernel=kernel, spp=int(spp), light_samples=int(light_samples), seed=int(seed),
                pipeline=pipeline, cooperative=bool(cooperative), direct=bool(direct),
                indirect=bool(indirect), threads=int(threads), hash_mode=hash_mode)


def render(scene: Scene, camera: Camera, photons: int = 1 << 18, radius: float | None = None,
           grid: str = "hash", gather: str = "radius", k: int = 50, spp: int = 1, seed: int = 0,
           kernel: str = "box", light_samples: int = 1, pipeline: str = "fused",
           cooperative: bool = False, direct: bool = True, indirect: bool = True, threads: int = 0,
           hash_mode: str = "auto", return_stats: bool = False, progressive: bool = False,
           passes: int = 16, time_budget: float | None = None, alpha: float = 2 / 3,
           snapshots: Sequence[int] = ()):
    """Render linear radiance, float32 (H, W, 3).

    Direct light by sampling the emitters with shadow rays; indirect light by density estimation
    in the photon map (grid 'hash' or 'kdtree'; gather 'radius' with no heap, or 'knn' with a
    heap of k; kernel 'box' or 'cone'). pipeline 'fused' or 'two-pass'; cooperative=True (two-pass,
    hash grid, radius gather) streams each photon once through a block of hit points in one cell.
    The same seed gives the same image for any thread count. return_stats=True also returns a
    dict of pass times (seconds) and counts.

    progressive=True: stochastic progressive photon mapping (consistent: converges to the exact
    image as passes grow). Each of `passes` passes (or fewer when `time_budget` seconds run out)
    takes one camera sample per pixel and `photons` new photons; `radius` is the initial radius,
    shrunk per pixel by the alpha rule. `snapshots` lists pass counts whose images are returned
    in stats['snapshots'] as (passes, seconds, image).
    """
    s = _settings(scene, photons, radius, grid, gather, k, kernel, spp, light_samples, seed, pipeline,
                  cooperative, direct, indirect, threads, hash_mode)
    if not progressive:
        if snapshots:
            raise ValueError("snapshots need progressive=True")
        image, stats = _core._render(scene, camera, **s)
        return (image, stats) if return_stats else image
    if isinstance(passes, bool) or not isinstance(passes, (int, np.integer)) or not 1 <= passes <= 1 << 24:
        raise ValueError(f"passes must be an integer in [1, 2^24], got {passes!r}")
    budget = 0.0 if time_budget is None else float(time_budget)
    if not math.isfinite(budget) or budget <= 0 and time_budget is not None:
        raise ValueError(f"time_budget must be positive and finite, got {time_budget!r}")
    alpha = float(alpha)
    if not 0 < alpha < 1:
        raise ValueError(f"alpha must be in (0, 1), got {alpha}")
    shots = [int(x) for x in snapshots]
    if any(x < 1 for x in shots):
        raise ValueError("snapshots must be positive pass counts")
    image, stats = _core._render_progressive(scene, camera, **s, passes=int(passes), time_budget=budget,
                                             alpha=alpha, snapshots=shots)
    return (image, stats) if return_stats else image


def render_stereo(scene: Scene, eyes: StereoCamera, reuse: bool = True, photons: int = 1 << 18,
                  radius: float | None = None, grid: str = "hash", gather: str = "radius", k: int = 50,
                  spp: int = 1, seed: int = 0, kernel: str = "box", light_samples: int = 1,
                  direct: bool = True, indirect: bool = True, threads: int = 0):
    """Render both eyes: (left, right, stats). With reuse=True the left eye writes the colour of
    each hit point the right eye can see into the right image (seed 001 §3.3); stats has
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


def save_image(path, image: np.ndarray) -> None:
    """Write linear radiance as EXR/HDR (float) or PNG/JPEG/TIFF (sRGB, 8 bit) via OpenImageIO.
    Writes to a temporary name first, so a failed write never leaves a complete-looking file."""
    import OpenImageIO as oiio

    path = Path(path)
    img = np.asarray(image, dtype=np.float32)
    if img.ndim != 3 or img.shape[2] != 3:
        raise ValueError(f"image must have shape (H, W, 3), got {img.shape}")
    ext = path.suffix.lower()
    if ext in (".exr", ".hdr"):
        data, fmt = img, "float"
    elif ext in (".png", ".jpg", ".jpeg", ".tif", ".tiff"):
        c = np.clip(np.nan_to_num(img), 0.0, 1.0)
        srgb = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
        data, fmt = (srgb * 255 + 0.5).astype(np.uint8), "uint8"
    else:
        raise ValueError(f"unsupported image format {ext!r} (use .exr, .hdr, .png, .jpg or .tif)")
    if not path.parent.is_dir():
        raise OSError(f"directory does not exist: {path.parent}")
    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    out = oiio.ImageOutput.create(str(tmp))
    if out is None:
        raise OSError(f"cannot write {path}: {oiio.geterror()}")
    spec = oiio.ImageSpec(img.shape[1], img.shape[0], 3, fmt)
    ok = out.open(str(tmp), spec) and out.write_image(np.ascontiguousarray(data))
    err = out.geterror()
    out.close()
    if not ok:
        tmp.unlink(missing_ok=True)
        raise OSError(f"cannot write {path}: {err}")
    tmp.replace(path)


def relmse(image: np.ndarray, reference: np.ndarray, eps: float = 1e-2) -> float:
    """Relative mean squared error, mean((x - ref)^2 / (ref^2 + eps)), over pixels and channels.
    eps keeps black pixels from dominating (the usual convention in rendering papers)."""
    image = np.asarray(image, dtype=np.float64)
    reference = np.asarray(reference, dtype=np.float64)
    if image.shape != reference.shape:
        raise ValueError(f"shape mismatch: {image.shape} vs {reference.shape}")
    return float(np.mean((image - reference) ** 2 / (reference ** 2 + eps)))
