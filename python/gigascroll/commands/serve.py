"""`gigascroll serve PACK --room scroll|hall|FILE`: serve a pack and its lit room to browsers
(the WebXR client; docs/serve-protocol.md). Prints the URL; Ctrl-C or SIGTERM stops it."""

from __future__ import annotations

import sys

from ..errors import UserError


def register(sub) -> None:
    p = sub.add_parser("serve", help="serve a pack and its lit room to a browser or headset",
                       description="Serve a tile pack and a lit gallery room over HTTP(S) to "
                                   "the WebXR client (loopback by default).")
    p.add_argument("pack", metavar="PACK", nargs="?", default=None,
                   help="pack directory (or --exhibition)")
    p.add_argument("--room", default=None,
                   help="gallery room: scroll, hall or a room file (.glb, .gltf, .obj, .ply); "
                        "required with PACK")
    from .exhibition_options import add_exhibition_option
    add_exhibition_option(p)
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1; a headset on the LAN needs "
                        "--tls-cert and --tls-key)")
    p.add_argument("--port", type=int, default=8000, help="port (default 8000; 0: a free one)")
    p.add_argument("--tls-cert", metavar="FILE", help="PEM certificate (serve HTTPS)")
    p.add_argument("--tls-key", metavar="FILE", help="PEM private key of --tls-cert")
    p.add_argument("--cache-dir", metavar="DIR",
                   help="where baked rooms are cached (default $XDG_CACHE_HOME/gigascroll/rooms "
                        "or ~/.cache/gigascroll/rooms)")
    p.add_argument("--threads", type=int, default=0, help="bake threads (0 = all cores)")
    from .light_quality import add_light_quality_options
    add_light_quality_options(p)
    from .display_options import add_display_options
    add_display_options(p, "scene.json's display block carries them to the client")
    p.set_defaults(func=run)


def _say(text: str) -> None:
    print(f"gigascroll serve: {text}", file=sys.stderr, flush=True)


def _announce(url: str) -> None:
    """The URL served; on every address (--host 0.0.0.0 or ::), also the URLs a headset on
    this machine's network opens, since 0.0.0.0 is no address to type."""
    from ..serve.run import network_urls
    print(f"serving {url}", flush=True)
    for other in network_urls(url):
        print(f"  on this machine's network: {other}", flush=True)


def _iiif_id(iiif) -> str:
    """The id the show's IIIF manifest gives itself (exhibit build's --base-url)."""
    import json
    try:
        return str(json.loads((iiif / "manifest.json").read_text(encoding="utf-8"))["id"])[:200]
    except (OSError, ValueError, KeyError, TypeError):
        return "no readable manifest.json"


def _cache_dir(args, show, content_hash: str):
    """--cache-dir; for a show whose bake (exhibit build's) holds this room's glb, the show's
    bake/ (read only: a miss bakes into the user cache, never into the show)."""
    if show is None or args.cache_dir is not None:
        return args.cache_dir
    from ..serve.room_bake import glb_damage, lighting_options, room_key
    from .light_quality import light_settings_of
    key = room_key(show.room, content_hash, lighting_options(light_settings_of(args, show.room)))
    glb = show.path / "bake" / f"{key}.glb"
    return glb.parent if glb.is_file() and glb_damage(glb) is None else None  # damaged: rebake elsewhere


def run(args) -> int:
    from .. import TilePack
    from ..outputs import signals_interrupt
    from ..serve import baked_room, make_app, pack_hash, serve_forever, tls_context
    from ..serve.run import LOOPBACK_HOSTS, listen_socket, log_to_stderr, raise_open_files_limit

    from .exhibition_options import open_exhibition
    if args.exhibition is None and (args.pack is None or args.room is None):
        raise UserError("give PACK --room ROOM, or --exhibition DIR")
    from .light_quality import check_light_budget, light_settings_of
    check_light_budget(args)
    if not 0 <= args.port <= 65535:
        raise UserError(f"--port must be in [0, 65535], got {args.port}")
    if args.cache_dir is not None and not args.cache_dir.strip():
        raise UserError("--cache-dir must name a directory")
    if (args.tls_cert is None) != (args.tls_key is None):
        raise UserError("TLS: --tls-cert and --tls-key go together")
    ssl_context = None
    if args.tls_cert:
        try:
            ssl_context = tls_context(args.tls_cert, args.tls_key)
        except OSError as e:  # ssl.SSLError is one
            raise UserError(f"TLS: cannot load --tls-cert {args.tls_cert} / --tls-key "
                            f"{args.tls_key}: {e.strerror or e}") from None
    elif args.host not in LOOPBACK_HOSTS:
        _say(f"warning: serving plain HTTP on {args.host}: a headset needs HTTPS off "
             "localhost for WebXR (give --tls-cert and --tls-key, or use adb reverse)")
    raise_open_files_limit()  # each visitor's connections hold descriptors
    try:
        sock = listen_socket(args.host, args.port)
    except OSError as e:
        raise UserError(f"cannot listen on {args.host}:{args.port}: {e.strerror or e}") from None
    show = open_exhibition(args)
    try:
        pack = show.pack if show is not None else TilePack(args.pack)
    except Exception as e:  # a missing or corrupt pack
        raise UserError(f"cannot open pack {args.pack}: {e}") from None
    content_hash = pack_hash(pack)
    try:
        from ..serve.room_bake import load_room_spec
        spec = show.room if show is not None else load_room_spec(args.room, pack)
        with signals_interrupt():  # SIGTERM during the bake: the same clean exit as Ctrl-C
            room = baked_room(args.room or "exhibition", pack, content_hash,
                              _cache_dir(args, show, content_hash),
                              threads=args.threads, announce=_say, spec=spec,
                              settings=light_settings_of(args, spec))
    except (OSError, ValueError) as e:
        raise UserError(f"room {args.room}: {e}") from None
    log_to_stderr()
    from .display_options import display_of
    display = display_of(args, room.spec)
    _say(f"display: EV100 {display.ev100:.2f} ({display.how}), tone {display.tone}")
    iiif = show.path / "iiif" if show is not None and (show.path / "iiif").is_dir() else None
    app = make_app(pack, room, content_hash, display=display, iiif_dir=iiif)
    if iiif is not None:
        _say(f"the show's IIIF folder at /iiif/ (manifest /iiif/manifest.json; its ids name "
             f"{_iiif_id(iiif)})")
    caught = serve_forever(app, args.host, args.port, ssl_context, sock=sock,
                           announce=_announce)
    _say(f"stopped ({caught})")
    return 0
