"""`gigascroll gallery [PACK] [--room ...] [--path ...] [--eye WxH] ... [--out DIR]`: walk
through the lit gallery and write the frames, the video, the report and the results (by
default next to the pack, PACK-walk/; the command prints where)."""

from __future__ import annotations

import os
import re
import time
from pathlib import Path

from ..errors import UserError
from .exhibition_options import require_pack_dir

DEFAULT_SECONDS = 6.0  # the default walk's and --look-at's length

BUILTIN_PAINTING = (30000, 1200)  # the built-in ink landscape used when no pack is given


def register(sub) -> None:
    p = sub.add_parser(
        "gallery", help="walk through the lit gallery: frames, video and report",
        description="Runs the gallery frame loop along a camera path: feedback, hash request "
        "processing, capped direct loading from the lock-free loader, the page-table update and "
        "the display pass at full per-eye resolution (right eye reusing the left eye's hits), "
        "lit by the photon map. Writes PNG frames (eyes side by side, magnifier inset), an "
        "H.264 MP4 of the walk (side-by-side stereo), report.md with plots and results.json.")
    p.add_argument("pack", nargs="?", metavar="PACK",
                   help="one tile pack (it may hold several paintings: gigascroll pack a.tif "
                        "b.tif -o gallery.pack); default: the built-in painting, synthesized "
                        "and packed once into the user cache ($XDG_CACHE_HOME/gigascroll, else "
                        "~/.cache/gigascroll)")
    p.add_argument("--room", default="scroll", help="scroll, hall, or a room file (glTF/OBJ/PLY)")
    p.add_argument("--path", default=None,
                   help="walk (along the painting, with stops and a close look; the default "
                        "without --exhibition) or a camera path JSON")
    p.add_argument("--tour", metavar="FILE", default=None,
                   help="a tour JSON file (docs/cameras-and-tours.md): keyframes walked along "
                        "centripetal Catmull-Rom curves (default with --exhibition: the show's "
                        "tour, every painting in turn)")
    from .exhibition_options import add_exhibition_option, add_look_at_options
    add_exhibition_option(p)
    add_look_at_options(p)
    p.add_argument("--eye", default="1800x1920", help="per-eye resolution WxH (default the headset's)")
    p.add_argument("--no-magnifier", action="store_true", help="no magnifier")
    p.add_argument("--lighting", choices=["baked", "full"], default="baked",
                   help="baked irradiance (default) or direct light and gather per pixel")
    p.add_argument("--seconds", type=float, default=None,
                   help="length of the walk: of the default walk and of --look-at's stand "
                        "(default 6); with a tour or a camera path, walk only its first "
                        "SECONDS (default: all of it)")
    p.add_argument("--out", default=None,
                   help="output directory (default: next to the pack, PACK-walk; without a "
                        "pack, gallery-walk in the working directory)")
    p.add_argument("--exr", action="store_true", help="also write each saved frame as linear EXR")
    from .display_options import add_display_options
    add_display_options(p, "the frames' EXRs stay linear radiance; results.json states what was "
                           "used")
    p.add_argument("--png-every", type=int, default=None,
                   help="keep every n-th frame as PNG (default: about 40 over the walk)")
    p.add_argument("--no-video", action="store_true", help="skip the MP4")
    p.add_argument("--no-oracle", action="store_true", help="skip the per-frame oracle comparison")
    p.add_argument("--no-reuse", action="store_true", help="trace the right eye in full")
    p.add_argument("--photons", type=int, default=None,
                   help="photons for the lighting (default: chosen by --quality)")
    from .light_quality import add_light_quality_options
    add_light_quality_options(p, "--photons")
    p.add_argument("--pace", action="store_true", help="sleep to the path's frame rate")
    p.add_argument("--threads", type=int, default=0, help="worker threads (0 = all cores)")
    p.add_argument("--fovea", type=float, default=None, metavar="DEG",
                   help="fixed foveation: a centred fovea DEG degrees wide and high traced at "
                        "full density, the periphery at 1/--fovea-factor per axis and requested "
                        "that much coarser (default: off)")
    p.add_argument("--fovea-factor", type=int, default=2, metavar="K",
                   help="with --fovea: the periphery's density is 1/K per axis (default 2)")
    p.set_defaults(func=run)


def parse_eye(text: str, option: str = "--eye") -> tuple[int, int]:
    """A WIDTHxHEIGHT option (--eye, view's --window) as (width, height), 16..16384 each."""
    m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", str(text))
    if not m:
        raise UserError(f"{option} must be WIDTHxHEIGHT, e.g. 1800x1920, got {str(text)[:40]!r}")
    # Sides of more than 9 digits are out of range whatever they are (and int() of thousands
    # of digits is refused by Python itself).
    w, h = (int(g.lstrip("0") or "0") if len(g.lstrip("0")) <= 9 else 10**9 for g in m.groups())
    if not (16 <= w <= 16384 and 16 <= h <= 16384):
        raise UserError(f"{option} must be between 16x16 and 16384x16384 pixels, got "
                        f"{w if w < 10**9 else 'huge'}x{h if h < 10**9 else 'huge'}")
    return w, h


def parse_foveation(degrees, factor, eye=(1800, 1920)):
    """--fovea DEG and --fovea-factor K as a Foveation (None when --fovea is not given),
    checked against the headset's field of view at the per-eye resolution `eye`."""
    from .. import views as v
    from ..walk.foveation import Foveation
    from ..views.exhibition import Headset
    if degrees is None:
        return None
    try:
        f = Foveation(float(degrees), int(factor))
        hs = Headset(width=eye[0], height=eye[1])
        f.layout(v.Camera((0, 0, 0), (0, 0, -1), (0, 1, 0), hs.tan_half_x, hs.tan_half_y,
                          eye[0], eye[1]))
        return f
    except (TypeError, ValueError, OverflowError) as e:
        raise UserError(f"--fovea / --fovea-factor: {e}") from None


def load_room(room: str, pack):
    from ..gallery import ROOM_NAMES, builtin_room
    if room in ROOM_NAMES:
        return builtin_room(room, pack)
    path = Path(room)
    if not path.is_file():
        raise UserError(f"--room must be {', '.join(ROOM_NAMES)} or a room file; {room!r} is "
                        "neither")
    from ..room.files import load_room as load_file
    return load_file(path, pack)


def load_path(path: str, room, seconds: float):
    from .. import views as v
    from ..walk.gallery_walk import walk_path
    if path == "walk":
        return walk_path(room, seconds)
    p = Path(path)
    if not p.is_file():
        raise UserError(f"--path must be 'walk' or a camera path JSON file; {path!r} is neither")
    return v.CameraPath.load(p)


def walk_camera_path(args, room, show, eye):
    """The walk's CameraPath: --look-at (standing there for --seconds), --tour FILE, --path,
    or with --exhibition and neither the show's tour; one of them at most."""
    from ..exhibit import ExhibitionError
    from ..exhibit.tours import check_inside, load_tour, tour_path
    from .exhibition_options import headset_view, look_at_pose
    given = [o for o, v in (("--look-at", args.look_at), ("--tour", args.tour),
                            ("--path", args.path)) if v is not None]
    if len(given) > 1:
        raise UserError(f"give one of {', '.join(given)}, not several")
    pose = look_at_pose(args, room, show, *headset_view(eye))
    try:
        if pose is not None:
            return standing_path(pose, _seconds(args))
        if args.tour is not None:
            tour = load_tour(args.tour)
            check_inside(tour, show.exhibition if show is not None else None)
            return first_seconds(tour_path(tour), args.seconds)
        if args.path is None and show is not None:
            return first_seconds(tour_path(show.tour), args.seconds)
    except (ExhibitionError, ValueError) as e:
        raise UserError(f"--tour: {e}" if args.tour else str(e)) from None
    if args.path not in (None, "walk"):
        return first_seconds(load_path(args.path, room, 0.0), args.seconds)
    return load_path("walk", room, _seconds(args))


def _seconds(args) -> float:
    return DEFAULT_SECONDS if args.seconds is None else args.seconds


def first_seconds(path, seconds: float | None):
    """The first `seconds` of a CameraPath (all of it when None or longer)."""
    import numpy as np

    from .. import views as v
    n = len(path) if seconds is None else min(len(path), max(1, int(round(seconds * path.fps))))
    if n == len(path):
        return path
    cut = (lambda a: None if a is None else np.asarray(a)[:n])
    return v.CameraPath(path.position[:n], path.forward[:n], path.up[:n],
                        cut(path.magnifier_target), cut(path.magnifier_normal), path.fps,
                        path.name)


def standing_path(pose, seconds: float):
    """A CameraPath standing at (eye, target) for `seconds` (the views' frame rate)."""
    import numpy as np

    from .. import views as v
    n = max(2, int(round(seconds * v.FPS)))
    eye, target = np.array(pose[0]), np.array(pose[1])
    fwd = target - eye
    up = [0.0, 1.0, 0.0] if abs(fwd[1]) < 0.999 * np.linalg.norm(fwd) else [0.0, 0.0, -1.0]
    return v.CameraPath(np.tile(eye, (n, 1)), np.tile(fwd, (n, 1)), np.tile(up, (n, 1)),
                        name="look-at")


def user_cache() -> Path:
    """$XDG_CACHE_HOME/gigascroll, else ~/.cache/gigascroll (serve's baked rooms live there
    too): data the commands make for themselves, kept between runs."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "gigascroll"


def builtin_pack(work: Path | None = None):
    """The built-in ink landscape at BUILTIN_PAINTING, synthesized and packed once into `work`
    (default: the user cache, whatever the working directory)."""
    from ..pack import TilePack, build_pack, synth_painting
    work = user_cache() if work is None else Path(work)
    pack_dir = work / "gallery-painting.pack"
    if (pack_dir / "manifest.json").is_file():
        return TilePack(pack_dir)
    print(f"no pack given: packing the built-in painting ({BUILTIN_PAINTING[0]} x "
          f"{BUILTIN_PAINTING[1]}) once into {os.path.abspath(pack_dir)}")
    work.mkdir(parents=True, exist_ok=True)
    tif = work / "gallery-painting.tif"
    synth_painting(tif, *BUILTIN_PAINTING, progress=True)
    pack = build_pack(tif, pack_dir, force=True, progress=True)
    tif.unlink(missing_ok=True)
    return pack


def run(args) -> int:
    from ..walk.record import prepare_output
    from ..outputs import refuse_input, signals_interrupt

    eye = parse_eye(args.eye)
    foveation = parse_foveation(args.fovea, args.fovea_factor, eye)
    if args.seconds is not None and not (args.seconds > 0 and args.seconds <= 3600):
        raise UserError(f"--seconds must be in (0, 3600], got {args.seconds}")
    if args.png_every is not None and args.png_every < 1:
        raise UserError("--png-every must be >= 1")
    if args.photons is not None and args.photons < 1:
        raise UserError("--photons must be >= 1")
    from .light_quality import check_light_budget
    check_light_budget(args)
    out = default_out(args)
    if args.pack is not None:  # a walk inside the pack would change the pack
        require_pack_dir(args.pack)  # the first thing to say
        try:
            refuse_input(out, args.pack, "the pack being walked")
        except OSError as e:
            raise UserError(f"--out {e}") from None
    tmp = prepare_output(out)  # fails early on an unwritable --out
    with signals_interrupt():  # SIGTERM / SIGHUP: the temporary output goes as for Ctrl-C
        try:
            results = _walk(args, out, tmp, eye, foveation)
        except BaseException:
            import shutil
            shutil.rmtree(tmp, ignore_errors=True)
            raise
    s = results["summary"]
    from ..walk.frame_rates import fps_text
    print(f"{s['frames']} frames at {eye[0]}x{eye[1]} per eye: {fps_text(s)}; display "
          f"{s['display_ms']:.1f} ms/frame (left {s['left_display_ms']:.1f}, right "
          f"{s['right_display_ms']:.1f} reusing {100 * s['reused_share']:.0f} %); hit rate "
          f"{s['hit_rate']:.3f}" + (f"; error vs oracle {s['error_mean']:.3g} mean, "
                                    f"{s['error_final']:.3g} last" if "error_mean" in s else ""))
    print(f"wrote {os.path.abspath(out)}/ (report.md, results.json, frames/"
          f"{', walk.mp4' if not args.no_video else ''})")
    return 0


def default_out(args) -> Path:
    """--out, else next to the pack (PACK-walk), else gallery-walk in the working directory."""
    from ..outputs import beside
    if args.out is not None:
        return Path(args.out)
    if getattr(args, "exhibition", None):
        return beside(args.exhibition, "walk")
    return beside(args.pack, "walk") if args.pack else Path("gallery-walk")


def _walk(args, out: Path, tmp: Path, eye, foveation) -> dict:
    """Opens the pack, room and path, lights the room and records the walk into `tmp`."""
    from ..walk.record import record_walk
    from ..walk.video import check_fps
    from ..walk.gallery_walk import GallerySource, GalleryWalk
    from ..pack import TilePack

    from .exhibition_options import open_exhibition
    show = open_exhibition(args, room_default="scroll")
    if show is not None:
        pack, room = show.pack, show.room
    elif args.pack:
        pack = TilePack(Path(args.pack))  # a pack's manifest: checked in run()
    else:
        pack = builtin_pack()
    if show is None:
        room = load_room(args.room, pack)
    path = walk_camera_path(args, room, show, eye)
    if not args.no_video:
        try:
            check_fps(path.fps)  # before the room is lit
        except ValueError as e:
            raise UserError(f"--path: {e}") from None
    from .display_options import display_of
    display = display_of(args, room, args.lighting)
    t0 = time.perf_counter()
    from .light_quality import light_settings_of
    source = GallerySource(room, pack, args.lighting, photons=args.photons,
                           threads=args.threads, response=display, light=light_settings_of(args, room))
    print(f"{source.name}: lit in {time.perf_counter() - t0:.1f} s "
          f"({source.light_stats.get('photons_stored', 0)} photons stored)")
    walk = GalleryWalk(source, pack, path, eye=eye, magnifier=not args.no_magnifier,
                       reuse=not args.no_reuse, oracle=not args.no_oracle, pace=args.pace,
                       threads=args.threads, foveation=foveation)
    settings = {"room": room.name if show is not None else args.room, "path": path.name,
                "exhibition": args.exhibition, "eye": f"{eye[0]}x{eye[1]}",
                "magnifier": not args.no_magnifier, "lighting": args.lighting,
                "seconds": round(len(path) / path.fps, 3), "reuse": not args.no_reuse,
                "photons": args.photons or source.light.photons, "light": source.light.describe(),
                "frames": len(path),
                "exposure": display.how if args.exposure.mode == "auto" else
                f"{args.exposure.mode} {args.exposure.value:g}", "tone": args.tone}
    if foveation is not None:
        settings["foveation"] = {"fovea_deg": foveation.fovea_deg,
                                 "factor": foveation.factor, "blend": foveation.blend}
    return record_walk(walk, out, exr=args.exr, png_every=args.png_every,
                       video=not args.no_video, progress=True, settings=settings, tmp=tmp)
