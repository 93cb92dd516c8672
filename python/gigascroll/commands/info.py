"""`gigascroll info`: describe a tile pack."""

from __future__ import annotations

import json


def register(sub) -> None:
    p = sub.add_parser("info", help="describe a tile pack",
                       description="Prints a tile pack's geometry, layout and paintings.")
    p.add_argument("pack", metavar="PACK", help="pack directory")
    p.add_argument("--json", action="store_true", help="print the manifest as JSON")
    p.add_argument("--verify", action="store_true",
                   help="also read every tile and check its checksum")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..pack import TilePack, pack_manifest, pack_summary, verify_pack
    pack = TilePack(args.pack)
    if args.json:
        print(json.dumps(pack_manifest(args.pack), indent=2))
    else:
        print(pack_summary(pack))
    if args.verify:
        n = verify_pack(pack, progress=not args.json)
        if not args.json:
            print(f"verified {n} tiles: all checksums match")
    return 0
