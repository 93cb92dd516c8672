"""Walking through the gallery (issue 14): the frame loop at the headset's resolution.

Per frame, with the lock-free loader in its own thread: the feedback pass (1/8 per axis for
the eyes, full 512 x 512 for the magnifier), hash request processing, capped direct loading,
the drain (physical cache and page table), the LRU update, and the display pass at full
per-eye resolution (sampling.DisplayPass: primary rays, trilinear VT albedo at the pixel's
level, times the scene's irradiance), the right eye reusing the left eye's hits. Each stage
is timed, the display split into rays, reuse, VT sampling and shading; each displayed frame
is compared with its oracle: the same display through a second virtual texture into which
every tile the frame needs was loaded synchronously.

The scene comes from a `FrameSource`: `ExhibitionSource` (the views' Embree scene of the
room's paintings and boxes, unlit) or the Gallery's (lit). The loop only uses the interface.
"""

from __future__ import annotations

import hashlib
import math
import statistics
import time
from dataclasses import dataclass, field

import numpy as np

from .. import _core
from .. import runtime
from .. import views as v
from ..display_mapping import Display, exposure_for_white, to_srgb8
from ..gallery.tile_keys import parent_keys
from ..room.spec import RoomSpec
from ..views.exhibition import Headset
from .frame_rates import FPS_MEANING
from .loop import frame_summary, load_stages, request_hit_rate, run_frames

__all__ = ["FrameSource", "ExhibitionSource", "GallerySource", "walk_path", "stops_of", "GalleryWalk", "WALK_STAGES", "DISPLAY_PARTS",
           "compose_frame", "tone_map", "lens_in_view", "parent_keys"]

# The loop's stages in order (VT-mobile-VR Table 5's columns, as frame_loop.STAGES) and the parts
# of the display pass.
WALK_STAGES = ("feedback", "processing", "issue", "drain", "update", "display")
DISPLAY_PARTS = ("rays", "reuse", "vt", "shade")


class FrameSource:
    """What the walk needs of a scene: the feedback pass, the display pass (one eye and a
    stereo pair) and the paintings' tile geometry for request processing, plus the exposure
    that maps its radiance to display values (1 for an unlit scene)."""

    name = "source"
    exposure = 1.0
    response = Display(1.0, "neutral")   # the camera response of its frames (display_mapping)
    lit = False
    tiles: list = []

    def feedback(self, camera, width: int, height: int, threads: int = 0) -> np.ndarray:
        raise NotImplementedError

    # out, out_left, out_right: arrays the source may render into and return (a stream of
    # frames keeps them); a source that cannot returns fresh arrays.
    def display(self, dpass, vt, camera, threads: int = 0, out=None) -> np.ndarray:
        raise NotImplementedError

    def display_stereo(self, dpass, vt, left, right, reuse: bool, threads: int = 0,
                       out_left=None, out_right=None):
        raise NotImplementedError

    def primary_rays(self, camera, threads: int = 0) -> tuple[float, int]:
        """The bare Embree primary-ray cast of the same pixels (the display's baseline)."""
        raise NotImplementedError


def pack_identity(pack) -> str | None:
    """A digest of the pack's manifest (its paintings, geometry, codec and sources): a frame
    source built from one pack must not stream another's tiles through its geometry."""
    manifest = getattr(pack, "manifest_json", None)
    if manifest is None:
        return None
    text = manifest() if callable(manifest) else manifest
    return hashlib.blake2b(str(text).encode("utf-8", "surrogatepass"), digest_size=16).hexdigest()


class ExhibitionSource(FrameSource):
    """A room's paintings in the views' `ExhibitionScene`, every other surface an occluder
    box (one per quad of the room), displayed unlit: radiance = albedo, occluders grey."""

    lit = False
    exposure = 1.0
    response = Display(1.0, "neutral", "unlit: radiance = albedo")

    def __init__(self, room: RoomSpec, pack):
        check_room_paintings(room, pack)
        self.pack_identity = pack_identity(pack)
        self.name = f"{room.name} (unlit)"
        scene = v.ExhibitionScene()
        self.tiles = [v.PaintingGeometry(p.width, p.height, pack.tile_size, pack.border)
                      for p in pack.paintings]
        for slot in room.paintings:
            pid = painting_index(pack, slot.painting)
            scene.add_painting(pid, self.tiles[pid], tuple(slot.origin), tuple(slot.u_axis),
                               tuple(slot.v_axis), slot.width_m, slot.height_m)
        for s in room.surfaces:
            verts = np.asarray(s.vertices, float)
            tris = np.asarray(s.triangles, int)
            for k in range(0, len(tris), 2):  # rooms are built of quads: two triangles each
                pts = verts[tris[k:k + 2].ravel()]
                lo, hi = pts.min(axis=0), pts.max(axis=0)
                thin = hi - lo < 1e-3
                lo, hi = np.where(thin, lo - 5e-4, lo), np.where(thin, hi + 5e-4, hi)
                scene.add_box(tuple(lo), tuple(hi))
        scene.commit()
        self.scene = scene
        self.lighting = _core.UnlitLighting()

    def feedback(self, camera, width, height, threads=0):
        return v.render_view(self.scene, camera, width, height, threads=threads,
                             display=False)["keys"]

    def display(self, dpass, vt, camera, threads=0, out=None):
        return dpass.render(self.scene, self.lighting, vt, camera, threads=threads)

    def display_stereo(self, dpass, vt, left, right, reuse, threads=0, out_left=None,
                       out_right=None):
        return dpass.render_stereo(self.scene, self.lighting, vt, left, right, reuse=reuse,
                                   threads=threads)

    def primary_rays(self, camera, threads=0):
        return _core.cast_primary_rays(self.scene, camera, threads)


class GallerySource(FrameSource):
    """The lit gallery (issue 13's `Gallery`): one Embree scene for the feedback pass and the
    display pass, irradiance baked once (lighting "baked") or computed per pixel ("full")."""

    lit = True

    def __init__(self, room: RoomSpec, pack, lighting: str = "baked", photons: int | None = None,
                 spacing: float | None = None, bake_samples: int | None = None, threads: int = 0,
                 exposure: float | None = None, response=None, light=None):
        """`light`: the light's LightSettings (gallery/quality.py; default: the room's at the
        default quality level); photons, spacing and bake_samples, when given, override it."""
        from ..gallery.exposure import room_display
        from ..gallery.gallery import Gallery
        if lighting not in ("baked", "full", "unlit"):
            raise ValueError(f"lighting must be baked, full or unlit, got {lighting!r}")
        check_room_paintings(room, pack)
        self.pack_identity = pack_identity(pack)
        self.gallery = Gallery.from_room(room, pack)
        self.lighting = lighting
        self.name = f"{room.name} ({lighting})"
        self.tiles = [v.PaintingGeometry(p.width, p.height, pack.tile_size, pack.border)
                      for p in pack.paintings]
        self.light_stats, self.light = {}, None
        t0 = time.perf_counter()
        if lighting != "unlit":
            from ..gallery.quality import apply_settings, light_settings
            self.light = light if light is not None else light_settings(room)
            # The photons read the paintings' pinned coarse levels: any VT of the pack will do.
            self.light_stats = apply_settings(self.gallery, self.light, threads=threads,
                                              bake=lighting == "baked", photons=photons,
                                              spacing=spacing, light_samples=bake_samples)
        self.light_seconds = time.perf_counter() - t0
        # response: a display_mapping.Display (default: auto exposure for the room, neutral
        # tone); a bare `exposure` factor keeps that factor with the neutral curve.
        if response is None:
            response = (room_display(room, lighting=lighting) if exposure is None else
                        Display(float(exposure), "neutral", "given factor"))
        self.response = response
        self.exposure = response.exposure

    def feedback(self, camera, width, height, threads=0):
        return self.gallery.render_view(camera, width, height, threads=threads)["keys"]

    # out / out_left, out_right: float32 (height, width, 3) arrays to render into (a stream of
    # frames reuses them: no fresh pages to fault in per frame); None: fresh arrays.
    def display(self, dpass, vt, camera, threads=0, out=None):
        return _core._gallery_display(dpass, self.gallery, vt, camera, self.lighting, threads,
                                      out)

    def display_stereo(self, dpass, vt, left, right, reuse, threads=0, out_left=None,
                       out_right=None):
        return _core._gallery_display_stereo(dpass, self.gallery, vt, left, right,
                                             self.lighting, reuse, threads=threads,
                                             out_left=out_left, out_right=out_right)

    def primary_rays(self, camera, threads=0):
        return _core._gallery_primary_rays(self.gallery, camera, threads)


def painting_index(pack, painting) -> int:
    """The pack's index of a slot's painting (a name or an index)."""
    names = [p.name for p in pack.paintings]
    if isinstance(painting, str):
        if painting not in names:
            raise ValueError(f"the room shows painting {painting!r}, which the pack does not "
                             f"hold (it has {', '.join(names) or 'none'})")
        return names.index(painting)
    if not 0 <= int(painting) < len(names):
        raise ValueError(f"the room shows painting {painting}, the pack has {len(names)}")
    return int(painting)


def check_room_paintings(room: RoomSpec, pack) -> None:
    if not room.paintings:
        raise ValueError(f"room {room.name!r} has no paintings")
    for slot in room.paintings:
        painting_index(pack, slot.painting)


def lit_exposure() -> float:
    """The exposure factor of `white=GALLERY_LUX` (display_mapping): a white painting under
    the gallery's target illuminance is exposed to paper white. Rooms expose automatically
    (gallery/exposure.py); this is the fixed figure for callers without a room."""
    from ..room.builtin import GALLERY_LUX

    return exposure_for_white(GALLERY_LUX)


def tone_map(linear: np.ndarray, exposure: float = 1.0, tone: str = "neutral") -> np.ndarray:
    """Linear radiance to 8-bit sRGB through the one camera response (display_mapping:
    exposure, the tone curve, the sRGB curve)."""
    return to_srgb8(linear, exposure, tone)


def lens_in_view(camera, centre, lens_right, radius_m: float):
    """Pixel centre and radius of a round lens (centre point, unit vector in its plane) in a
    camera's image, or None when the lens is behind the eye."""
    pos, fwd = np.array(camera.position), np.array(camera.forward)
    right, up = np.array(camera.right), np.array(camera.up)
    w, h = camera.resolution

    def project(p):
        rel = np.asarray(p) - pos
        z = rel @ fwd
        if z <= 1e-6:
            return None
        return (np.array([(rel @ right) / z / camera.tan_half_x + 1,
                          1 - (rel @ up) / z / camera.tan_half_y]) * [w / 2, h / 2])
    c = project(centre)
    e = project(np.asarray(centre) + radius_m * np.asarray(lens_right))
    if c is None or e is None:
        return None
    return c, float(np.linalg.norm(e - c))


def _paste_disc(img: np.ndarray, lens: np.ndarray, centre, radius: float) -> None:
    """Draws the square lens image into img as a disc (nearest sample), with a dark rim."""
    h, w = img.shape[:2]
    x0, x1 = max(0, int(centre[0] - radius) - 1), min(w, int(centre[0] + radius) + 2)
    y0, y1 = max(0, int(centre[1] - radius) - 1), min(h, int(centre[1] + radius) + 2)
    if x0 >= x1 or y0 >= y1 or radius < 1:
        return
    ys, xs = np.mgrid[y0:y1, x0:x1]
    dx, dy = (xs + 0.5 - centre[0]) / radius, (ys + 0.5 - centre[1]) / radius
    r2 = dx * dx + dy * dy
    n = lens.shape[0]
    inside = r2 <= 1.0
    sx = np.clip(((dx + 1) / 2 * n).astype(int), 0, n - 1)
    sy = np.clip(((dy + 1) / 2 * n).astype(int), 0, n - 1)
    region = img[y0:y1, x0:x1]
    region[inside] = lens[sy[inside], sx[inside]]
    rim = (r2 > 1.0) & (r2 <= (1 + 3 / max(radius, 1)) ** 2)
    region[rim] = 0


def compose_frame(left: np.ndarray, right: np.ndarray, magnifier: np.ndarray | None = None,
                  lenses=(None, None), inset: bool = True) -> np.ndarray:
    """The two eyes side by side (linear float images, same size), the magnifier's image
    composited where its lens sits in each eye (`lenses`: (centre, radius) per eye or None)
    and, with `inset`, as a square in the lower right corner of each eye."""
    eyes = [left.copy(), right.copy()]
    if magnifier is not None:
        for img, lens in zip(eyes, lenses):
            if lens is not None:
                _paste_disc(img, magnifier, lens[0], lens[1])
            if inset:
                h, w = img.shape[:2]
                s = min(h, w, max(8, min(h, w) // 3))  # a third of the eye, at least 8 px
                idx = (np.arange(s) * magnifier.shape[0] // s)
                img[h - s:, w - s:] = magnifier[idx][:, idx]
                img[h - s:h - s + 1, w - s:] = 0
                img[h - s:, w - s:w - s + 1] = 0
    return np.concatenate(eyes, axis=1)


@dataclass
class GalleryWalk:
    """Runs a camera path through a FrameSource's scene whose painting p is painting p of
    `pack`, at `eye` = (width, height) per eye.

    reuse: the right eye reuses the left eye's hits (False: traced in full).
    oracle: compare each displayed frame with the same frame through a virtual texture that
    holds every tile the frame asks for and their trilinear parents (loaded synchronously).
    pace: sleep to the path's frame boundaries (False: flat out).
    wait_loads: block each frame until that frame's loads arrived (deterministic tests).
    on_frame(frame, record, images): called with the frame's record and its display images
    (left, right, magnifier or None, lenses) before the next frame starts (the next frame
    renders into the same arrays: copy what you keep).
    foveation: a walk.foveation.Foveation (None: off): each eye's fovea traced at full
    density, its periphery at a lower one, and both requested by their own cameras."""
    source: FrameSource
    pack: object
    path: v.CameraPath
    eye: tuple[int, int] = (1800, 1920)
    magnifier: bool = True
    reuse: bool = True
    oracle: bool = True
    per_frame: int = 16
    slots: tuple[int, int] = (30, 30)
    oracle_slots: tuple[int, int] = (64, 64)
    pace: bool = False
    wait_loads: bool = False
    threads: int = 0
    foveation: object = None
    records: list = field(default_factory=list, init=False)

    def __post_init__(self):
        w, h = self.eye
        if not (isinstance(w, (int, np.integer)) and isinstance(h, (int, np.integer))) \
                or w < 16 or h < 16 or w > 16384 or h > 16384:
            raise ValueError(f"eye resolution must be between 16 x 16 and 16384 x 16384 "
                             f"pixels, got {w} x {h}")
        if self.per_frame <= 0:
            raise ValueError("per_frame (the direct-loading threshold) must be > 0")
        if len(self.pack.paintings) < len(self.source.tiles):
            raise ValueError("the pack lacks paintings the scene shows")
        built = getattr(self.source, "pack_identity", None)
        if built is not None and built != pack_identity(self.pack):
            raise ValueError("the frame source was built from another pack than the walk's "
                             "(their manifests differ): build the source from the walk's pack")
        self.headset = Headset(width=int(w), height=int(h))
        if self.foveation is not None:  # a fovea wider than the eye fails here, not mid-walk
            self.foveation.layout(self.cameras(0)[0][0])

    def cameras(self, frame: int):
        """The frame's views: (camera, feedback w, feedback h) for left, right[, magnifier]."""
        return v.frame_cameras(self.path, frame, headset=self.headset,
                               magnifier=v.MAGNIFIER if self.magnifier else None)

    def lenses(self, frame: int, views) -> tuple:
        """Where the magnifier's 10 cm lens sits in each eye's image (None: not this frame)."""
        if len(views) < 3:
            return (None, None)
        mag = views[2][0]
        right = np.array(mag.right)
        return tuple(lens_in_view(cam, np.array(mag.position), right,
                                  v.MAGNIFIER.lens_size / 2) for cam, _, _ in views[:2])

    def open_state(self, loader) -> "_LoopState":
        """The loop's run-time state (virtual textures, processors, display passes) around a
        started TileLoader: what run() and an interactive viewer step frames with."""
        pack, src = self.pack, self.source
        vt = runtime.VirtualTexture(pack, self.slots)
        return _LoopState(
            vt=vt, lookup=_core.VirtualTextureLookup(vt),
            proc=v.make_processor("hash", src.tiles, self.threads), truth=v.BasicProcessor(),
            direct=v.DirectLoading(self.per_frame),
            levels=np.array([t.levels for t in src.tiles], np.int64), loader=loader,
            oracle_vt=runtime.VirtualTexture(pack, self.oracle_slots) if self.oracle else None,
            passes=[_core.DisplayPass() for _ in range(4)],
            foveated=None if self.foveation is None else _foveated_displays(self.foveation))

    def run(self, progress: bool = False, on_frame=None) -> dict:
        """Runs the path through the one frame loop (loop.run_frames); the summary."""
        run_frames(self, progress, on_frame)
        return self.summary()

    def loader_options(self) -> dict:
        return {"mode": "lockfree", "threads": 1}

    def progress_label(self) -> str:
        return f"walk {self.source.name}"

    def step(self, frame: int, state: "_LoopState", views=None, moving: bool | None = None,
             foveate: bool = True):
        """One frame: (record, (left, right, magnifier or None, lenses)); the images are the
        state's, overwritten by the next step. views: the frame's
        (camera, feedback w, feedback h) list (default: the path's frame); moving: whether the
        pose changes after this frame (default: from the path); foveate=False: this frame
        without the walk's foveation (an interactive viewer's toggle)."""
        vt, lookup, proc, truth = state.vt, state.lookup, state.proc, state.truth
        direct, levels, loader, oracle_vt = state.direct, state.levels, state.loader, state.oracle_vt
        dpass, mpass, opass, ompass = state.passes
        src, thr = self.source, self.threads
        t = {}
        t0 = time.perf_counter()
        if views is None:
            views = self.cameras(frame)
        if moving is None:
            moving = frame + 1 < len(self.path) and _pose_changes(self.path, frame)
        foveation = self.foveation if foveate else None
        foveated = state.foveated if foveation is not None else None
        feedback_views = (views if foveation is None else
                          foveation.feedback_views(views, self.headset.feedback_scale))
        buffers = [src.feedback(cam, fw, fh, thr) for cam, fw, fh in feedback_views]
        t["feedback"] = time.perf_counter() - t0

        t0 = time.perf_counter()
        new_set = proc.process(buffers, lookup, frame)
        # Trilinear filtering also reads the level above each request: those tiles are
        # requested too (the distinct requests' parents, a quarter as many at most).
        parents = parent_keys(new_set["requests"], levels)
        commands = new_set["commands"]
        if parents.size:
            missing = vt.request(parents)
            if missing.size:
                commands = np.concatenate([commands, missing])
        t["processing"] = time.perf_counter() - t0

        def issue_tiles():
            direct.set_commands(commands)
            return direct.issue(lookup)
        issue, arrived = load_stages(t, issue_tiles, vt, loader, direct, new_set["responses"],
                                     self.wait_loads, wait_timeout=30)

        t0 = time.perf_counter()
        (lc, _, _), (rc, _, _) = views[0], views[1]
        if foveated is None:
            left, right = src.display_stereo(dpass, vt, lc, rc, self.reuse, thr,
                                             state.image("left", lc), state.image("right", rc))
            ls, rs = dpass.left_stats, dpass.right_stats
        else:
            left, right = foveated[0].display_stereo(src, vt, lc, rc, self.reuse, thr)
            ls, rs = foveated[0].left_stats, foveated[0].right_stats
        mag = (src.display(mpass, vt, views[2][0], thr, state.image("magnifier", views[2][0]))
               if len(views) > 2 else None)
        t["display"] = time.perf_counter() - t0
        ms = mpass.left_stats if mag is not None else None
        parts = {}
        for part in DISPLAY_PARTS:
            key = f"{part}_seconds"
            parts[part] = ls[key] + rs[key] + (ms[key] if ms else 0.0)

        hit_rate, n_requests = request_hit_rate(truth, buffers, lookup, frame)
        rec = {
            "frame": frame, **{f"{s}_ms": 1e3 * t[s] for s in WALK_STAGES},
            **{f"display_{p}_ms": 1e3 * parts[p] for p in DISPLAY_PARTS},
            "left_display_ms": 1e3 * (ls["total_seconds"]),
            "right_display_ms": 1e3 * (rs["total_seconds"]),
            "magnifier_display_ms": 1e3 * ms["total_seconds"] if ms else 0.0,
            "reused_share": rs["reused"] / max(1, rs["pixels"]),
            "traced_rays": int(ls["traced"] + rs["traced"]),
            "total_ms": 1e3 * sum(t.values()), "requests": n_requests, "hit_rate": hit_rate,
            "issued": int(issue.size), "loaded": int(arrived.size),
            "moving": bool(moving),
            "magnifier": mag is not None,
        }
        if oracle_vt is not None:
            t0 = time.perf_counter()
            needed = np.unique(np.concatenate([b.ravel() for b in buffers]))
            needed = needed[needed != v.NO_REQUEST]
            needed = np.concatenate([needed, parent_keys(needed, levels)])
            missing = oracle_vt.request(needed)
            if missing.size:
                for key in zip(*(a.tolist() for a in v.unpack_requests(missing))):
                    oracle_vt.insert(key, self.pack.read_tile(*key))
            if foveated is None:
                ol, orr = src.display_stereo(opass, oracle_vt, lc, rc, self.reuse, thr,
                                             state.image("oracle_left", lc),
                                             state.image("oracle_right", rc))
            else:  # the oracle of a foveated frame is the same foveated frame, all resident
                ol, orr = foveated[1].display_stereo(src, oracle_vt, lc, rc, self.reuse, thr)
            om = (src.display(ompass, oracle_vt, views[2][0], thr,
                              state.image("oracle_magnifier", views[2][0]))
                  if mag is not None else None)
            shown = [left, right] + ([mag] if mag is not None else [])
            truth_imgs = [ol, orr] + ([om] if om is not None else [])
            e = src.exposure
            diff = [np.abs(a - b) * e for a, b in zip(shown, truth_imgs)]
            rec["error"] = float(np.mean([d.mean() for d in diff]))
            rec["error_max"] = float(max(d.max() for d in diff))
            rec["wrong_pixels"] = float(np.mean([(d.max(axis=2) > 1 / 512).mean() for d in diff]))
            rec["oracle_ms"] = 1e3 * (time.perf_counter() - t0)
        images = (left, right, mag, self.lenses(frame, views))
        return rec, images

    def summary(self) -> dict:
        r = self.records
        if not r:
            return {}
        out = {
            "frames": len(r), "eye": list(self.eye), "path_fps": self.path.fps,
            **frame_summary(r, WALK_STAGES),
            **{f"display_{p}_ms": statistics.mean(x[f"display_{p}_ms"] for x in r)
               for p in DISPLAY_PARTS},
            "left_display_ms": statistics.mean(x["left_display_ms"] for x in r),
            "right_display_ms": statistics.mean(x["right_display_ms"] for x in r),
            "reused_share": statistics.mean(x["reused_share"] for x in r),
            "stops": stops_of(r),
            "fps_meaning": dict(FPS_MEANING),  # what fps and fps_from_frame_time measure
        }
        if "error" in r[0]:
            out["oracle_ms"] = statistics.mean(x["oracle_ms"] for x in r)
            out["error_mean"] = statistics.mean(x["error"] for x in r)
            out["error_final"] = r[-1]["error"]
        return out


@dataclass
class _LoopState:
    vt: object
    lookup: object
    proc: object
    truth: object
    direct: object
    levels: np.ndarray
    loader: object
    oracle_vt: object
    passes: list
    foveated: list | None = None  # with foveation: the displays of the frame and its oracle
    # The display images, kept between frames (a frame's images are valid until the next
    # step: on_frame and viewers copy what they keep).
    images: dict = field(default_factory=dict)

    def image(self, name: str, camera) -> np.ndarray:
        w, h = camera.resolution
        a = self.images.get(name)
        if a is None or a.shape != (h, w, 3):
            a = self.images[name] = np.empty((h, w, 3), np.float32)
        return a


def _foveated_displays(foveation) -> list:
    from .foveation import FoveatedDisplay
    return [FoveatedDisplay(foveation), FoveatedDisplay(foveation)]


def stops_of(records: list) -> list[dict]:
    """Each stop of the path (a run of frames at one pose, to the next move or the end) with
    its display latency: frames from the stop's first frame until every request is resident
    at its level (hit rate 1), and until the frame equals its oracle (error 0)."""
    stops, i, n = [], 0, len(records)
    while i < n:
        if records[i]["moving"] or (i > 0 and not records[i - 1]["moving"]):
            i += 1
            continue
        j = i
        while j + 1 < n and not records[j]["moving"]:
            j += 1
        # records[i..j] show one pose (frame j's pose differs from j + 1's, or j is last).
        seg = records[i:j + 1]
        sharp = next((k for k, x in enumerate(seg) if x["hit_rate"] == 1.0), None)
        exact = next((k for k, x in enumerate(seg) if x.get("error", 1) == 0.0), None)
        stops.append({"first_frame": records[i]["frame"], "frames": len(seg),
                      "display_latency_frames": None if sharp is None else sharp + 1,
                      "exact_after_frames": None if exact is None else exact + 1})
        i = j + 1
    return [s for s in stops if s["frames"] > 1]


def _pose_changes(path: v.CameraPath, frame: int) -> bool:
    a = (path.position[frame], path.forward[frame], path.up[frame])
    b = (path.position[frame + 1], path.forward[frame + 1], path.up[frame + 1])
    return not all(np.array_equal(x, y) for x, y in zip(a, b))


def walk_path(room: RoomSpec, seconds: float = 6.0, fps: float = v.FPS,
              distance: float = 0.40, close: float = 0.28) -> v.CameraPath:
    """The default walk along the room's first painting: walk at 0.5 m/s facing it from
    `distance`, stop, step up to `close` for a close look (the magnifier looking at the
    point ahead all along), stop, step back and walk on, stop at the end. The parts' shares
    of `seconds`: walk 30 %, stop 15 %, approach 10 %, close look 15 %, back 10 %, walk 10 %,
    stop 10 %."""
    if not (math.isfinite(seconds) and 0 < seconds <= 3600):
        raise ValueError(f"--seconds must be in (0, 3600], got {seconds}")
    if not room.paintings:
        raise ValueError(f"room {room.name!r} has no paintings to walk along")
    slot = room.paintings[0]
    origin, u = np.array(slot.origin, float), np.array(slot.u_axis, float)
    va = np.array(slot.v_axis, float)
    facing = np.cross(u, va)  # a normal of the painting; the room's side is chosen below
    facing /= np.linalg.norm(facing)
    centre = origin + va * slot.height_m / 2
    if room.camera_eye is not None and np.dot(np.array(room.camera_eye) - centre, facing) < 0:
        facing = -facing
    up = np.array([0.0, 1.0, 0.0]) if abs(facing[1]) < 0.9 else -va

    def frames(share):
        return max(2, int(round(share * seconds * fps)))
    n_walk, n_stop, n_in, n_look, n_out, n_walk2, n_end = (
        frames(s) for s in (0.30, 0.15, 0.10, 0.15, 0.10, 0.10, 0.10))
    span = slot.width_m
    speed = min(0.5, 0.6 * span / ((n_walk + n_walk2) / fps))
    s0 = max(0.1, 0.5 * span - 0.5 * speed * (n_walk + n_walk2) / fps)
    along, dist = [], []

    def seg(n, a0, a1, d0, d1):
        t = (np.arange(n) + 1) / n  # the segment's end, not its start (the last one's end)
        along.extend(a0 + (a1 - a0) * t)
        dist.extend(d0 + (d1 - d0) * t)
    a1 = s0 + speed * n_walk / fps
    seg(n_walk, s0, a1, distance, distance)
    seg(n_stop, a1, a1, distance, distance)
    seg(n_in, a1, a1, distance, close)
    seg(n_look, a1, a1, close, close)
    seg(n_out, a1, a1, close, distance)
    a2 = a1 + speed * n_walk2 / fps
    seg(n_walk2, a1, a2, distance, distance)
    seg(n_end, a2, a2, distance, distance)
    along, dist = np.array(along), np.array(dist)
    n = len(along)
    target = centre + along[:, None] * u
    pos = target + dist[:, None] * facing
    fwd = np.tile(-facing, (n, 1))
    ups = np.tile(up, (n, 1))
    normal = np.tile(facing, (n, 1))
    return v.CameraPath(pos, fwd, ups, target, normal, fps, f"walk:{room.name}")
