"""`gigascroll render SCENE -o out.exr`: render a built-in scene with the photon mapper and
print the time of each pass. `gigascroll render --room scroll|hall|FILE --pack PACK -o still.exr`
renders a still of a gallery room with the pack's paintings (lighting baked or full)."""

from __future__ import annotations

import math

from pathlib import Path

from ..errors import UserError

FORMATS = (".exr", ".hdr", ".png", ".jpg", ".jpeg", ".tif", ".tiff")


def register(sub) -> None:
    from ..photon import BUILTIN_SCENES

    p = sub.add_parser("render", help="render a built-in scene with the photon mapper",
                       description="Render a built-in scene (photon mapping on Embree) to EXR or PNG.",
                       epilog="With --room the still applies --photons, --radius, --seed, --threads, "
                              "--no-indirect, --spp (a square), --light-samples and --disc / "
                              "--sphere; it refuses (exit 2) --progressive, --passes, "
                              "--time-budget, --kernel cone, --grid hash|kdtree, --gather knn, -k, "
                              "--pipeline two-pass and --cooperative, which the gallery does not have.")
    p.add_argument("scene", nargs="?", choices=sorted(BUILTIN_SCENES),
                   help="built-in scene (or --room for a gallery room)")
    p.add_argument("--room", help="gallery room: scroll, hall or a room file (.glb, .gltf, .obj, .ply)")
    p.add_argument("--pack", help="tile pack whose paintings hang in --room")
    from .exhibition_options import add_exhibition_option, add_look_at_options
    add_exhibition_option(p)
    add_look_at_options(p)
    p.add_argument("--camera", metavar="EX,EY,EZ,TX,TY,TZ[,FOV]",
                   help="eye and target in metres and the vertical field of view in degrees "
                        "(default: the scene's camera, or the room's suggested view at 60 degrees)")
    p.add_argument("--lighting", choices=["baked", "full", "unlit"], default=None,
                   help="--room: irradiance baked once per lighting (default), per pixel (full), or none")
    p.add_argument("-o", "--output", required=True, help="output image (.exr, .hdr: linear; .png, .jpg: sRGB)")
    from .display_options import add_display_options
    add_display_options(p, "applies to .png, .jpg and .tif; .exr and .hdr stay linear radiance "
                           "(a scene's auto: factor 1)")
    p.add_argument("--width", type=int, default=256)
    p.add_argument("--height", type=int, default=256)
    p.add_argument("--photons", type=int, default=None,
                   help="photons emitted (default 2^18; --room: chosen by --quality)")
    p.add_argument("--radius", type=float, default=None,
                   help="gather radius (default 0.02 x the scene's scale: 0.02 in the Cornell box)")
    p.add_argument("--grid", choices=["adaptive", "hash", "kdtree"], default="adaptive",
                   help="photon search structure (default adaptive; hash is "
                        "VR-photon-mapping's grid)")
    p.add_argument("--gather", choices=["radius", "knn"], default="radius")
    p.add_argument("-k", type=int, default=None, help="photons of the k-nearest gather (default 50)")
    p.add_argument("--kernel", choices=["box", "cone"], default="box",
                   help="gather kernel (--room: box only, the gallery's gather)")
    p.add_argument("--spp", type=int, default=None,
                   help="camera samples per pixel (default 4; progressive renders take one per pass). "
                        "--room: a square k x k (default 1), the still supersampled on a k x k "
                        "sub-pixel grid and averaged in linear radiance")
    p.add_argument("--light-samples", type=int, default=None,
                   help="emitter samples per shading point, stratified (default 16, 1 per pass "
                        "with --progressive); --room: per pixel of lighting full and per point of "
                        "the bake (default 16)")
    p.add_argument("--seed", type=int, default=0)
    from .light_quality import add_light_quality_options
    add_light_quality_options(p, "--room: --photons, --light-samples and --spp")
    p.add_argument("--pipeline", choices=["fused", "two-pass"], default="fused")
    p.add_argument("--cooperative", action="store_true", help="cooperative gather (two-pass pipeline)")
    p.add_argument("--no-indirect", action="store_true",
                   help="direct light only (skips the photon pass; --room too)")
    p.add_argument("--threads", type=int, default=0, help="worker threads (0 = all cores)")
    p.add_argument("--progressive", action="store_true",
                   help="stochastic progressive photon mapping: --passes passes (or fewer within "
                        "--time-budget), the radius shrinking per pixel; converges to the exact image "
                        "(not for --room: refused)")
    p.add_argument("--passes", type=int, default=None, help="progressive passes (default 16)")
    p.add_argument("--time-budget", type=float, default=None,
                   help="progressive: stop after this many seconds")
    disc = p.add_mutually_exclusive_group()
    disc.add_argument("--disc", dest="disc", action="store_true", default=None,
                      help="gather over the surface disc (no edge darkening or leaks; the default "
                           "for box radius gathers of scenes; --room too)")
    disc.add_argument("--sphere", dest="disc", action="store_false",
                      help="gather over the sphere (VR-photon-mapping's estimator; "
                           "--room's default)")
    p.set_defaults(func=run)


def _camera_numbers(text: str) -> list[float]:
    import math

    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        raise UserError(f"--camera wants EX,EY,EZ,TX,TY,TZ[,FOV] numbers, got {text!r}") from None
    if len(values) not in (6, 7) or not all(math.isfinite(v) for v in values):
        raise UserError(f"--camera wants 6 or 7 finite numbers, got {text!r}")
    if len(values) == 7 and not 0 < values[6] < 180:
        raise UserError(f"--camera: the field of view must be in (0, 180) degrees, got {values[6]:g}")
    if values[:3] == values[3:6]:
        raise UserError("--camera: eye and target must differ")
    return values


# The scene renderer's options a room's still (the gallery core) does not have: refused with
# one line rather than ignored. (given, option, why)
def _refused_room_options(args) -> list[tuple[bool, str, str]]:
    return [
        (args.progressive, "--progressive", "the gallery has no progressive photon mapping; "
                                            "use --spp and --photons"),
        (args.passes is not None, "--passes", "it counts progressive passes"),
        (args.time_budget is not None, "--time-budget", "it bounds progressive passes"),
        (args.kernel != "box", f"--kernel {args.kernel}", "the gallery gathers with the box kernel"),
        (args.grid != "adaptive", f"--grid {args.grid}", "the gallery's photon map is the adaptive grid"),
        (args.gather != "radius", f"--gather {args.gather}", "the gallery gathers within a radius"),
        (args.k is not None, "-k", "it counts photons of the k-nearest gather"),
        (args.pipeline != "fused", f"--pipeline {args.pipeline}", "the gallery shades each pixel in one pass"),
        (args.cooperative, "--cooperative", "it is a mode of the two-pass pipeline"),
    ]


def _room_still_options(args) -> dict:
    """What the scene renderer's options become for a room's still: keyword arguments of
    Gallery.still (spp) and Gallery.light; the ones the gallery lacks raise UserError."""
    import math

    for given, option, why in _refused_room_options(args):
        if given:
            raise UserError(f"{option} does not apply to --room: {why}")
    spp = args.spp  # None: the light settings' (--quality)
    if spp is not None and (spp < 1 or math.isqrt(spp) ** 2 != spp):
        raise UserError(f"--spp with --room must be a square (1, 4, 9, 16, ...): k x k samples "
                        f"per pixel, got {spp}")
    options = {"spp": spp, "seed": args.seed, "threads": args.threads,
               "indirect": not args.no_indirect}
    if args.photons is not None:
        options["photons"] = args.photons
    if args.radius is not None:
        options["radius"] = args.radius
    if args.disc is not None:
        options["disc"] = args.disc
    if args.light_samples is not None:
        options["light_samples"] = args.light_samples
    return options


def run_room(args, out: Path) -> int:
    from .. import TilePack
    from ..gallery import Gallery, builtin_room
    from ..room.builtin import ROOM_NAMES

    if args.scene:
        raise UserError("give either a built-in SCENE or --room, not both")
    from .exhibition_options import open_exhibition
    show = open_exhibition(args)
    if show is None and not args.room:
        raise UserError("--look-at needs --room ROOM --pack PACK or --exhibition DIR")
    if show is None and not args.pack:
        raise UserError("--room needs --pack PACK")
    options = _room_still_options(args)
    if show is not None:
        return _still(args, out, show.pack, show.room, options, show)
    try:
        pack = TilePack(args.pack)
    except Exception as e:  # a missing or corrupt pack
        raise UserError(f"cannot open pack {args.pack}: {e}") from None
    try:
        if args.room in ROOM_NAMES:
            spec = builtin_room(args.room, pack)
        else:
            from ..room.files import load_room

            spec = load_room(args.room, pack)
        gallery = Gallery.from_room(spec, pack)
    except (OSError, ValueError) as e:
        raise UserError(f"room {args.room}: {e}") from None
    return _still(args, out, pack, spec, options, None, gallery)


def _still(args, out: Path, pack, spec, options: dict, show=None, gallery=None) -> int:
    """Renders and writes the still of a room (--room or --exhibition's)."""
    import time

    from ..gallery import Gallery
    from ..photon import save_image
    from .display_options import display_of
    from .exhibition_options import look_at_pose

    if gallery is None:
        try:
            gallery = Gallery.from_room(spec, pack)
        except (OSError, ValueError) as e:
            raise UserError(f"room {spec.name}: {e}") from None
    cam = _camera_numbers(args.camera) if args.camera else None
    fov = cam[6] if cam and len(cam) == 7 else 60.0
    if args.look_at is not None and cam is not None:
        raise UserError("give --camera or --look-at, not both")
    pose = look_at_pose(args, spec, show, fov, args.width / args.height)
    if pose is not None:
        cam = [*pose[0], *pose[1]]
    camera = gallery.camera((args.width, args.height), fov=fov,
                            eye=cam[:3] if cam else None, target=cam[3:6] if cam else None)
    from .light_quality import light_settings_of
    settings = light_settings_of(args, spec)
    capped = ""
    if not options["spp"]:  # the level's rays per pixel, as many as fit 2^26 samples
        from ..gallery.quality import still_spp

        options = {**options, "spp": still_spp(settings.spp, args.width, args.height)}
        if options["spp"] < settings.spp:
            capped = f" (the level's {settings.spp}, capped at 2^26 samples)"
    if args.width * args.height * options["spp"] > 1 << 26:
        raise UserError(f"--room: {args.width} x {args.height} pixels x {options['spp']} spp is more "
                        "than 2^26 samples")
    t0 = time.perf_counter()
    try:
        _light_room(gallery, settings, args.lighting or "baked", options)
        image = gallery.still(camera, lighting=args.lighting or "baked", progress=True, spp=options["spp"])
    except ValueError as e:
        raise UserError(str(e)) from None
    total = time.perf_counter() - t0
    display = display_of(args, spec, args.lighting or "baked")
    save_image(out, image, display)
    st = gallery.stats
    ms = lambda s: f"{1000 * s:9.1f} ms"  # noqa: E731
    print(f"room {spec.name}: {gallery.triangle_count} triangles, {gallery.painting_count} paintings, "
          f"{args.width}x{args.height}, {options['spp']} spp{capped}, lighting {args.lighting or 'baked'}")
    if gallery.lit:
        print(f"light     {settings.describe()}")
    if gallery.lit and args.no_indirect:
        print("photons   skipped (--no-indirect: direct light only)")
    elif gallery.lit:
        print(f"photons   {ms(st['photon_seconds'])}  ({options.get('photons', settings.photons)} emitted, {st['photons_stored']} stored, "
              f"radius {st['radius']:.4g} m)")
        print(f"grid      {ms(st['build_seconds'])}  (build)")
    if gallery.baked:
        print(f"bake      {ms(st['bake_seconds'])}  ({st['bake_points']} points, spacing {st['spacing']:.3g} m)")
    print(f"total     {ms(total)}")
    _say_display(out, display)
    print(f"wrote {out}")
    return 0


def _light_room(gallery, settings, lighting: str, options: dict) -> None:
    """Lights (and bakes) the room at the knob's settings, the options given explicitly
    (--photons, --radius, --disc, --light-samples, --seed, --threads, --no-indirect) over them."""
    from .. import runtime

    if lighting == "unlit":
        return
    given = {k: options[k] for k in ("photons", "radius", "disc", "light_samples", "seed", "threads",
                                     "indirect") if k in options}
    gallery.light(runtime.VirtualTexture(gallery.pack, (30, 30)), **{**settings.light_options(), **given})
    if lighting == "baked":
        bake = settings.bake_options()
        if "light_samples" in options:
            bake["light_samples"] = options["light_samples"]
        gallery.bake(threads=options.get("threads", 0), progress=True, **bake)


def _say_display(out: Path, display) -> None:
    if out.suffix.lower() in (".exr", ".hdr"):
        print("display   none: linear radiance")
    else:
        print(f"display   EV100 {display.ev100:.2f} (x{display.exposure:.4g}, {display.how}), "
              f"tone {display.tone}, sRGB")


def run(args) -> int:
    from ..photon import BUILTIN_SCENES, builtin_scene, render, save_image

    out = Path(args.output)
    if out.suffix.lower() not in FORMATS:
        raise UserError(f"unsupported output format {out.suffix!r}; use one of {', '.join(FORMATS)}")
    if not out.parent.is_dir():
        raise UserError(f"output directory does not exist: {out.parent}")
    if args.pack:  # an image inside the pack would change the pack
        from ..outputs import refuse_input
        try:
            refuse_input(out, args.pack, "the pack being rendered")
        except OSError as e:
            raise UserError(str(e)) from None
    if args.width <= 0 or args.height <= 0 or args.width > 16384 or args.height > 16384:
        raise UserError("--width and --height must be in [1, 16384]")
    if args.photons is not None and args.photons <= 0:
        raise UserError("--photons must be positive")
    from .light_quality import check_light_budget
    check_light_budget(args)
    if args.light_samples is not None and not 1 <= args.light_samples <= 4096:
        raise UserError("--light-samples must be in [1, 4096]")
    if args.room or args.exhibition or args.look_at is not None:
        return run_room(args, out)
    if args.scene is None:
        raise UserError("give a built-in SCENE or --room ROOM --pack PACK")
    for given, option in ((args.pack, "--pack"), (args.lighting, "--lighting"), (args.quality, "--quality"),
                          (args.light_budget, "--light-budget")):
        if given is not None:
            raise UserError(f"{option} applies to --room; the built-in scene {args.scene} is "
                            "lit by the photon mapper's gather")
    radius = args.radius if args.radius is not None else 0.02 * BUILTIN_SCENES[args.scene]
    spp = args.spp if args.spp is not None else (1 if args.progressive else 4)
    # 16 stratified: 1 left salt-and-pepper on the Cornell box's tall block and the floor's
    # penumbrae; progressive passes average their own samples
    light_samples = args.light_samples or (1 if args.progressive else 16)
    scene, camera = builtin_scene(args.scene, resolution=(args.width, args.height))
    if args.camera:  # the scene's own camera's field of view unless given; up is +y
        from .._core import Camera
        cam = _camera_numbers(args.camera)
        try:
            camera = Camera(tuple(cam[:3]), tuple(cam[3:6]), (0.0, 1.0, 0.0),
                            cam[6] if len(cam) == 7 else camera.fov, (args.width, args.height))
        except ValueError as e:
            raise UserError(f"--camera: {e}") from None
    photons = 1 << 18 if args.photons is None else args.photons
    image, st = render(scene, camera, photons=photons, radius=radius, grid=args.grid,
                       gather=args.gather, k=50 if args.k is None else args.k, kernel=args.kernel,
                       spp=spp, light_samples=light_samples, seed=args.seed,
                       pipeline=args.pipeline, cooperative=args.cooperative,
                       indirect=not args.no_indirect, threads=args.threads, return_stats=True,
                       progressive=args.progressive, passes=16 if args.passes is None else args.passes,
                       time_budget=args.time_budget, disc=args.disc)
    from .display_options import display_of
    display = display_of(args)
    save_image(out, image, display)
    ms = lambda s: f"{1000 * s:9.1f} ms"  # noqa: E731
    print(f"{args.scene}: {scene.triangle_count} triangles, {args.width}x{args.height}, {spp} spp, "
          f"{light_samples} light samples, radius {radius:g}")
    if args.progressive:
        print(f"progressive {st['passes']} passes, mean final radius {st['mean_radius']:g}")
    if st["photon_pass_skipped"]:
        print("photon pass   skipped (no indirect light needed)")
    else:
        print(f"photons   {ms(st['photon_seconds'])}  ({photons} emitted, {st['photons_stored']} stored)")
        print(f"{args.grid:<9} {ms(st['build_seconds'])}  (build)")
    if args.pipeline == "two-pass":
        print(f"trace     {ms(st['trace_seconds'])}  (primary rays and direct light)")
    print(f"gather    {ms(st['gather_seconds'])}  ({st['gathers']} gathers, {st['gathers_skipped']} skipped;"
          f" {st['shadow_rays']} shadow rays, {st['shadow_rays_skipped']} skipped)")
    print(f"total     {ms(st['total_seconds'])}")
    _say_display(out, display)
    print(f"wrote {out}")
    return 0
