"""`gigascroll exhibit build show.toml -o show/`: an exhibition file (docs/exhibitions.md) to
a show directory: the paintings packed (a given pack used as is, or given packs' paintings
merged in without re-encoding; an unchanged pack is not made again), the room built, the light baked (the glb `serve --exhibition` shows) and the
tour written. `render`, `gallery`, `view` and `serve` then take `--exhibition show/`."""

from __future__ import annotations

import os

from ..errors import UserError

DEFAULT_BASE_URL = "http://localhost:8000/iiif"


def register(sub) -> None:
    p = sub.add_parser("exhibit", help="build a show from an exhibition file",
                       description="An exhibition file (docs/exhibitions.md) to a show "
                                   "directory, which render, gallery, view and serve take "
                                   "with --exhibition.")
    actions = p.add_subparsers(dest="action", metavar="ACTION")
    actions.required = True
    b = actions.add_parser("build", help="exhibition file (TOML) to a show directory")
    b.add_argument("exhibition", metavar="EXHIBITION.toml")
    b.add_argument("-o", "--output", required=True, metavar="DIR",
                   help="the show directory (made by this command; a show it made before is "
                        "replaced, its unchanged pack reused)")
    b.add_argument("--no-bake", action="store_true",
                   help="skip baking the light (serve then bakes it when it starts)")
    b.add_argument("--base-url", default=DEFAULT_BASE_URL, metavar="URL",
                   help="where the show's iiif/ folder will be served: the IIIF Presentation "
                        "manifest and the Image API ids point there (default "
                        f"{DEFAULT_BASE_URL}: `gigascroll serve --exhibition DIR` serves it "
                        "on its default port, as does `python -m http.server 8000` run in the "
                        "show directory)")
    b.add_argument("--no-iiif", action="store_true",
                   help="skip the IIIF export (Image API tiles and Presentation 3.0 manifest)")
    b.add_argument("--threads", type=int, default=0, help="worker threads (0 = all cores)")
    from .light_quality import add_light_quality_options
    add_light_quality_options(b)
    b.add_argument("--workers", type=int, default=0,
                   help="pack on this many Dask workers (a local cluster, as pack --workers; "
                        "default 0: in this process)")
    b.set_defaults(func=run)


def _bake(threads: int, args=None):
    def bake(gallery, spec, pack, directory):
        from ..outputs import write_bytes
        from ..serve import pack_hash
        from ..serve.room_bake import bake_glb, lighting_options, room_key
        from .light_quality import light_settings_of
        settings = light_settings_of(args, spec)
        key = room_key(spec, pack_hash(pack), lighting_options(settings))
        data, stats = bake_glb(gallery, spec, pack, threads, settings)
        write_bytes(directory / f"{key}.glb", data)
        return {"glb": f"bake/{key}.glb", "bake_points": stats.get("bake_points"),
                "seconds": stats.get("photon_seconds", 0) + stats.get("build_seconds", 0)
                + stats.get("bake_seconds", 0)}
    return bake


def run(args) -> int:
    from ..exhibit.build import build_show
    from ..exhibit.schema import ExhibitionError
    from ..outputs import signals_interrupt
    if not 0 <= args.threads <= 4096:
        raise UserError("--threads must be in [0, 4096]")
    if not 0 <= args.workers <= 1024:
        raise UserError("--workers must be in [0, 1024]")
    from .light_quality import check_light_budget
    check_light_budget(args)
    try:
        with signals_interrupt():
            record = build_show(args.exhibition, args.output, progress=True,
                                threads=args.threads, workers=args.workers,
                                bake=None if args.no_bake else _bake(args.threads, args),
                                iiif_base=None if args.no_iiif else args.base_url)
    except ExhibitionError as e:
        raise UserError(str(e)) from None
    pack = ("the previous build's pack reused (unchanged)" if record["reused_pack"] else
            "packed" if record["packed"] else "shown from the given pack as is (no labels)")
    if record.get("merged_packs") and not record["reused_pack"]:
        pack += (f", with the paintings of {len(record['merged_packs'])} given pack(s) "
                 "merged in (tiles copied, not re-encoded)")
    print(f"{record['paintings']} paintings: {pack}"
          + (f", light baked ({record['bake']['bake_points']} points)" if "bake" in record else "")
          + f", {record['seconds']:.1f} s")
    print(f"wrote {os.path.abspath(args.output)}/ (exhibition.json, tour.json, build.json"
          + (", paintings.pack" if record["packed"] or record["reused_pack"] else "")
          + (", bake/" if "bake" in record else "")
          + (", iiif/manifest.json" if "iiif" in record else "") + ")")
    return 0
