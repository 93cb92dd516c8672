"""`gigascroll view PACK [--room ...]`: a desktop window onto the live gallery loop.

Keys: W / S walk forward and back, A / D step left and right, arrow keys (or a mouse drag)
turn, R / F up and down, M toggles the magnifier, V toggles the fixed foveation (--fovea's,
or a 30 degree fovea at 1/2 density without it), P saves the window's frame (--screenshot),
T starts and stops recording the walk as a tour (keyframes every 0.25 s, written to
--record-tour when it stops), Esc quits. An overlay shows the frame rate, the stage times and the primary rays the eyes
traced; the eyes' resolution adapts so the window stays responsive (each frame's display is
upscaled to the window)."""

from __future__ import annotations

import dataclasses
import math
import os
import re
import string
import sys
import time
from pathlib import Path

from ..errors import UserError
from .exhibition_options import is_pack_dir, require_pack_dir


def register(sub) -> None:
    p = sub.add_parser("view", help="a window onto the live gallery loop",
                       description=__doc__.split("\n\n", 1)[1].replace("\n", " "))
    p.add_argument("pack", nargs="?", default=None, help="tile pack (or --exhibition)")
    from .exhibition_options import add_exhibition_option, add_look_at_options
    add_exhibition_option(p)
    add_look_at_options(p)
    p.add_argument("--record-tour", metavar="FILE", default=None,
                   help="where T writes the recorded tour (default: next to the pack or show, "
                        "NAME-tour-{n}.json; {n} a counter)")
    p.add_argument("--room", default="scroll", help="scroll, hall, or a room file")
    p.add_argument("--lighting", choices=["baked", "full", "unlit"], default="baked")
    from .display_options import add_display_options
    add_display_options(p, "screenshots show the same")
    p.add_argument("--window", default="1200x640", help="window size WxH (both eyes side by side)")
    p.add_argument("--eye", default=None,
                   help="initial per-eye resolution WxH (default: half the window's width)")
    p.add_argument("--target-fps", type=float, default=20.0,
                   help="the resolution adapts to hold this frame rate (default 20)")
    p.add_argument("--photons", type=int, default=None,
                   help="photons for the lighting (default: chosen by --quality)")
    from .light_quality import add_light_quality_options
    add_light_quality_options(p, "--photons")
    p.add_argument("--per-frame", type=int, default=16, help="tiles loaded per frame at most")
    p.add_argument("--screenshot", default=None,
                   help="file pattern P writes the window's frame to ({n}: a counter, which "
                        "skips files already there; .png or .jpg; default: next to the pack, "
                        "PACK-view-{n}.png)")
    p.add_argument("--quit-after", type=float, default=None, help="close after this many seconds")
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--fovea", type=float, default=None, metavar="DEG",
                   help="start foveated (as gigascroll gallery --fovea): a centred fovea DEG "
                        "degrees wide and high at full density, the periphery at 1/K (V toggles)")
    p.add_argument("--fovea-factor", type=int, default=2, metavar="K",
                   help="with --fovea: the periphery's density is 1/K per axis (default 2)")
    p.set_defaults(func=run)


def run(args) -> int:
    from .gallery import parse_eye, parse_foveation
    win_w, win_h = parse_eye(args.window, "--window")
    eye = parse_eye(args.eye) if args.eye else (win_w // 2, win_h)
    if not (args.target_fps > 0 and math.isfinite(args.target_fps)):
        raise UserError("--target-fps must be positive")
    if args.quit_after is not None and not (math.isfinite(args.quit_after)
                                            and 0 <= args.quit_after <= 1e7):
        raise UserError(f"--quit-after must be a number of seconds in [0, 1e7], got "
                        f"{args.quit_after}")
    if (args.pack is None) == (args.exhibition is None):
        raise UserError("give a PACK or --exhibition DIR (one of them)")
    anchor = args.pack or args.exhibition
    # The default is beside the pack, valid whenever the pack is (checked before the window).
    args.screenshot = (screenshot_pattern(args.screenshot) if args.screenshot is not None
                       else default_screenshot(anchor))
    # Shots inside the pack would change the pack (a path that is no pack is said later,
    # after the options: bad options fail first).
    is_pack = args.pack is not None and is_pack_dir(args.pack)
    from ..outputs import refuse_input
    if is_pack:
        try:
            refuse_input(Path(args.screenshot.format(n=0)), args.pack, "the pack being viewed")
        except OSError as e:
            raise UserError(f"--screenshot {e}") from None
    args.record_tour = tour_pattern(args.record_tour, anchor)
    if is_pack:  # nor a recorded tour
        try:
            refuse_input(Path(args.record_tour.format(n=0)), args.pack, "the pack being viewed")
        except OSError as e:
            raise UserError(f"--record-tour {e}") from None
    # Bad options fail before the display is looked for, so they are reported everywhere.
    foveation = parse_foveation(args.fovea, args.fovea_factor, eye)
    from .light_quality import check_light_budget
    check_light_budget(args)
    if sys.platform.startswith("linux") and not os.environ.get("DISPLAY") \
            and not os.environ.get("WAYLAND_DISPLAY"):
        raise UserError("no display to open a window on (DISPLAY is not set); "
                        "use `gigascroll gallery` to write the walk to files")
    from ..pack import TilePack
    from .exhibition_options import headset_view, look_at_pose, open_exhibition
    from .gallery import load_room
    show = open_exhibition(args, room_default="scroll")
    if show is not None:
        pack, room = show.pack, show.room
    else:
        pack = TilePack(require_pack_dir(args.pack))
        room = load_room(args.room, pack)
    args.pose = look_at_pose(args, room, show, *headset_view(eye))
    try:
        import pyglet
        pyglet.options["shadow_window"] = False
        window = pyglet.window.Window(win_w, win_h, caption="gigascroll view", resizable=True,
                                      vsync=False)
    except Exception as e:  # noqa: BLE001 (pyglet raises several kinds for "no display")
        raise UserError(f"cannot open a window: {str(e).splitlines()[0] if str(e) else type(e).__name__}") from None
    return Viewer(window, pack, room, args, eye, foveation).run()


SCREENSHOT_FORMATS = (".png", ".jpg", ".jpeg")


def tour_pattern(text: str | None, anchor: str) -> str:
    """--record-tour: a .json path whose only field is {n} (default: beside the pack or
    show, NAME-tour-{n}.json), in an existing directory."""
    from ..outputs import beside
    if text is None:
        return str(beside(anchor, "tour-")).replace("{", "{{").replace("}", "}}") + "{n}.json"
    try:
        fields = [f for _, f, _, _ in string.Formatter().parse(text) if f is not None]
        if any(f != "n" for f in fields):
            raise ValueError("its only field may be {n}, the recording's counter")
        first = Path(text.format(n=0))
    except (ValueError, KeyError, IndexError) as e:
        raise UserError(f"--record-tour {text[:80]!r}: not a file pattern ({e})") from None
    if "\0" in text or first.suffix.lower() != ".json" or not first.parent.is_dir():
        raise UserError(f"--record-tour {text[:80]!r}: expected a .json file in an existing "
                        "directory")
    return text


def default_screenshot(pack: str) -> str:
    """The screenshots' default pattern: next to the pack, PACK-view-{n}.png (braces in the
    pack's own name escaped, so only {n} is a field)."""
    from ..outputs import beside
    prefix = str(beside(pack, "view-"))
    return prefix.replace("{", "{{").replace("}", "}}") + "{n}.png"


def screenshot_pattern(text: str) -> str:
    """--screenshot checked before the window opens: a path whose only replacement field is
    {n} (the shot's counter, with a format spec if wanted), ending in .png or .jpg, in an
    existing directory; without {n}, a file that is not there yet. UserError otherwise."""
    try:
        fields = [f for _, f, _, _ in string.Formatter().parse(text) if f is not None]
        if any(f != "n" for f in fields):
            raise ValueError("its only field may be {n}, the shot's counter")
        specs = [s for _, f, s, _ in string.Formatter().parse(text) if f is not None]
        if any(int(w) > 64 for s in specs for w in re.findall(r"[0-9]+", s or "")):
            raise ValueError("its field's width is at most 64")
        names = [text.format(n=k) for k in (0, 1, 99999)]
    except (ValueError, KeyError, IndexError, AttributeError, TypeError) as e:
        raise UserError(f"--screenshot {text[:80]!r}: not a file pattern ({e})") from None
    first = Path(names[0])
    if "\0" in text or first.suffix.lower() not in SCREENSHOT_FORMATS:
        raise UserError(f"--screenshot {text[:80]!r}: the file must end in "
                        f"{', '.join(SCREENSHOT_FORMATS)}")
    if not first.parent.is_dir():
        raise UserError(f"--screenshot {text[:80]!r}: no such directory {first.parent}")
    if fields and len(set(names)) < 3:
        raise UserError(f"--screenshot {text[:80]!r}: {{n}} must make each shot's name differ")
    if not fields and (first.exists() or first.is_symlink()):
        raise UserError(f"--screenshot {text[:80]!r}: the file exists (add {{n}} for a counter)")
    return text


class Viewer:
    """The window, the pose, and the live loop stepping one frame per redraw."""

    def __init__(self, window, pack, room, args, eye, foveation=None):
        import numpy as np

        from .. import runtime
        from .. import views as v
        from ..walk.foveation import Foveation
        from ..walk.gallery_walk import GallerySource, GalleryWalk, walk_path
        from .display_options import display_of
        self.np, self.v, self.window, self.args = np, v, window, args
        from .light_quality import light_settings_of
        self.source = GallerySource(room, pack, args.lighting, photons=args.photons,
                                    threads=args.threads, light=light_settings_of(args, room),
                                    response=display_of(args, room, args.lighting))
        path = walk_path(room, seconds=0.05)
        if args.per_frame < 1:
            raise UserError("--per-frame must be >= 1")
        # The walk always holds a foveation so V can switch it on; --fovea starts it on.
        self.foveate = foveation is not None
        self.shown_foveate = None
        self.walk = GalleryWalk(self.source, pack, path, eye=eye, oracle=False,
                                per_frame=args.per_frame, threads=args.threads,
                                foveation=foveation or Foveation())
        self.loader = runtime.TileLoader(pack, mode="lockfree", threads=1)
        self.state = self.walk.open_state(self.loader)
        self.position = np.array(path.position[0])
        self.yaw = math.atan2(path.forward[0][0], path.forward[0][2])
        self.pitch = 0.0
        pose = getattr(args, "pose", None)
        if pose is not None:  # --look-at: in front of the painting, looking at its centre
            self.position = np.array(pose[0], float)
            f = np.array(pose[1], float) - self.position
            self.yaw = math.atan2(f[0], f[2])
            self.pitch = max(-1.4, min(1.4, math.atan2(f[1], math.hypot(f[0], f[2]))))
        self.recording = None  # [(position, target, time)] while T records a tour
        self.tours = 0
        self.focus = 0.40  # magnifier distance ahead (its target on the painting)
        self.magnifier = True
        self.eye = list(eye)
        self.base = tuple(eye)
        self.scale = 1.0
        self.frame = 0
        self.keys = pyglet_key_state(window)
        self.last = None
        self.texture = None
        self.shots = 0
        self.written: set[str] = set()
        self.want_shot = False
        self.start = time.perf_counter()
        self.record = None
        self.fps = 0.0
        import pyglet
        self.label = pyglet.text.Label("", x=8, y=window.height - 8, anchor_y="top",
                                       font_size=10, color=(255, 255, 160, 255), multiline=True,
                                       width=max(200, window.width - 16))
        window.push_handlers(on_draw=self.on_draw, on_key_press=self.on_key_press,
                             on_mouse_drag=self.on_mouse_drag, on_close=self.on_close)

    # --- pose --------------------------------------------------------------------------------
    def forward(self):
        cp = math.cos(self.pitch)
        return self.np.array([math.sin(self.yaw) * cp, math.sin(self.pitch),
                              math.cos(self.yaw) * cp])

    def views(self):
        np, v = self.np, self.v
        from ..views.exhibition import Headset
        w, h = (max(16, int(self.base[0] * self.scale)), max(16, int(self.base[1] * self.scale)))
        self.eye = [w, h]
        f = self.forward()
        path = v.CameraPath(self.position[None], f[None], np.array([[0.0, 1.0, 0.0]]),
                            (self.position + self.focus * f)[None] if self.magnifier else None,
                            (-f)[None] if self.magnifier else None)
        # The magnifier's resolution adapts with the eyes' (its feedback stays at its display's).
        mag = dataclasses.replace(v.MAGNIFIER, resolution=max(32, int(v.MAGNIFIER.resolution * self.scale)))
        return v.frame_cameras(path, 0, headset=Headset(width=w, height=h),
                               magnifier=mag if self.magnifier else None)

    def move(self, dt: float) -> bool:
        from pyglet.window import key
        k = self.keys
        f = self.forward()
        flat = self.np.array([f[0], 0.0, f[2]])
        flat /= max(1e-9, self.np.linalg.norm(flat))
        right = self.np.cross(flat, [0.0, 1.0, 0.0])
        step = 0.6 * dt
        d = self.np.zeros(3)
        d += step * flat * (k[key.W] - k[key.S])
        d += step * right * (k[key.D] - k[key.A])
        d[1] += step * (k[key.R] - k[key.F])
        turn = 1.2 * dt
        yaw = turn * (k[key.RIGHT] - k[key.LEFT])
        pitch = turn * (k[key.UP] - k[key.DOWN])
        self.position = self.position + d
        self.yaw += yaw
        self.pitch = max(-1.4, min(1.4, self.pitch + pitch))
        return bool(d.any() or yaw or pitch)

    # --- events ------------------------------------------------------------------------------
    def on_key_press(self, symbol, modifiers):
        from pyglet.window import key
        if symbol == key.ESCAPE:
            self.on_close()
            return True
        if symbol == key.M:
            self.magnifier = not self.magnifier
        if symbol == key.V:
            self.foveate = not self.foveate
        if symbol == key.P:
            self.want_shot = True  # saved right after the next frame is drawn
        if symbol == key.T:
            self.toggle_recording()
        return None

    def toggle_recording(self):
        """T: start recording the walk as tour keyframes, or stop and write the tour."""
        if self.recording is None:
            self.recording = []
            self.record_start = time.perf_counter()
            print("tour: recording (T stops)", flush=True)
            return
        keys, self.recording = self.recording, None
        if len(keys) < 2:
            print("tour: too short to keep (under 2 keyframes)", flush=True)
            return
        from ..exhibit.tours import Tour, save_tour
        pattern = self.args.record_tour
        name = pattern.format(n=self.tours)
        while pattern.format(n=0) != pattern.format(n=1) and os.path.lexists(name):
            self.tours += 1
            name = pattern.format(n=self.tours)
        self.tours += 1
        try:
            save_tour(Tour(*map(list, zip(*keys)), name="recorded"), name)
        except (OSError, ValueError) as e:
            print(f"tour: {e}", flush=True)
            return
        print(f"tour: {len(keys)} keyframes written to {os.path.abspath(name)}", flush=True)

    def record_keyframe(self):
        """While recording: a keyframe every 0.25 s (position, 2 m ahead, time)."""
        if self.recording is None:
            return
        t = time.perf_counter() - self.record_start
        if not self.recording or t - self.recording[-1][2] >= 0.25:
            f = self.forward()
            self.recording.append((self.position.copy(), self.position + 2.0 * f, t))

    def on_mouse_drag(self, x, y, dx, dy, buttons, modifiers):
        self.yaw += 0.005 * dx
        self.pitch = max(-1.4, min(1.4, self.pitch + 0.005 * dy))

    def on_close(self):
        self.window.close()
        import pyglet
        pyglet.app.exit()
        return True

    def screenshot(self):
        """Saves the window's frame (outputs.write_image: never half a file). The counter
        skips files it did not write; a failing write is one line, the session goes on."""
        import pyglet

        from ..outputs import write_image
        pattern = self.args.screenshot
        name = pattern.format(n=self.shots)
        counted = pattern.format(n=0) != pattern.format(n=1)
        while counted and os.path.lexists(name) and name not in self.written:
            self.shots += 1
            name = self.args.screenshot.format(n=self.shots)
        self.shots += 1
        if os.path.lexists(name) and name not in self.written:
            print(f"screenshot: {name} exists and was not written here; not replaced", flush=True)
            return
        img = pyglet.image.get_buffer_manager().get_color_buffer().get_image_data()
        rgb = self.np.frombuffer(img.get_bytes("RGB", img.width * 3), self.np.uint8)
        try:
            write_image(name, rgb.reshape(img.height, img.width, 3)[::-1])
        except (OSError, ValueError) as e:
            print(f"screenshot: {e}", flush=True)
            return
        self.written.add(name)
        print(f"screenshot: {os.path.abspath(name)}", flush=True)

    def tick(self, dt):
        """One frame of the loop; the resolution adapts toward the target frame rate."""
        np = self.np
        moved = self.move(dt if dt < 0.5 else 0.5)
        self.record_keyframe()
        t0 = time.perf_counter()
        rec, (left, right, mag, lenses) = self.walk.step(self.frame, self.state,
                                                         views=self.views(), moving=moved,
                                                         foveate=self.foveate)
        from ..walk.gallery_walk import compose_frame
        rgb = self.source.response.srgb8(compose_frame(left, right, mag, lenses))
        frame_s = time.perf_counter() - t0
        self.fps = 0.8 * self.fps + 0.2 / max(frame_s, 1e-6) if self.frame else 1 / frame_s
        target = 1.0 / self.args.target_fps
        if frame_s > 1.2 * target:
            self.scale = max(0.1, self.scale * 0.85)
        elif frame_s < 0.6 * target:
            self.scale = min(1.0, self.scale * 1.1)
        self.record = rec
        if self.foveate != self.shown_foveate:  # the first frame, and each V after it
            self.shown_foveate = self.foveate
            print(f"foveation {'on' if self.foveate else 'off'}: frame {self.frame}, "
                  f"{rec['traced_rays']} rays traced", flush=True)
        self.frame += 1
        import pyglet
        h, w = rgb.shape[:2]
        img = pyglet.image.ImageData(w, h, "RGB", np.ascontiguousarray(rgb[::-1]).tobytes())
        self.texture = img.get_texture()
        self.window.invalid = True

    def on_draw(self):
        self.window.clear()
        if self.texture is not None:
            self.texture.blit(0, 0, width=self.window.width, height=self.window.height)
        r = self.record
        if r:
            f = self.walk.foveation
            fovea = f"fovea {f.fovea_deg:g} deg 1/{f.factor}" if self.foveate else "fovea off"
            self.label.text = (
                f"{self.fps:5.1f} fps  eye {self.eye[0]}x{self.eye[1]}  hit {r['hit_rate']:.2f}"
                f"  magnifier {'on' if self.magnifier else 'off'} (M)  {fovea} (V)"
                f"  rays {r['traced_rays']}\n"
                + "  ".join(f"{k} {r[k + '_ms']:.1f}" for k in
                            ("feedback", "processing", "issue", "drain", "update"))
                + "\ndisplay " + "  ".join(f"{p} {r['display_' + p + '_ms']:.1f}" for p in
                                           ("rays", "reuse", "vt", "shade")) + " ms")
            self.label.y = self.window.height - 8
            self.label.draw()
        if self.want_shot and self.texture is not None:
            self.want_shot = False
            self.screenshot()

    def run(self) -> int:
        import pyglet
        pyglet.clock.schedule(self.tick)
        if self.args.quit_after is not None:
            pyglet.clock.schedule_once(lambda dt: self.on_close(), self.args.quit_after)
        try:
            pyglet.app.run()
        finally:
            self.loader.close()
        rays = self.record["traced_rays"] if self.record else 0
        print(f"view: {self.frame} frames, last eye {self.eye[0]}x{self.eye[1]}, "
              f"foveation {'on' if self.foveate else 'off'}, {rays} rays traced in the last "
              "frame", flush=True)
        return 0


def pyglet_key_state(window):
    from pyglet.window import key
    state = key.KeyStateHandler()
    window.push_handlers(state)
    return state
