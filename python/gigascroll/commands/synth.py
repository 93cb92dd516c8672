"""`gigascroll synth`: write the built-in ink-landscape painting as a tiled BigTIFF."""

from __future__ import annotations

from pathlib import Path

from ..errors import UserError

# VT-mobile-VR Table 4: the test paintings' sizes.
TABLE4 = [(152089, 6083), (196301, 5197), (159010, 4339), (102680, 5229), (109321, 7183),
          (117968, 4722), (91403, 11161), (119177, 3858)]


def register(sub) -> None:
    p = sub.add_parser("synth", help="write the built-in procedural ink-landscape painting",
                       description="Writes the deterministic built-in painting (an ink landscape "
                       "with detail down to single pixels) as a tiled BigTIFF, streamed in bands. "
                       "VT-mobile-VR Table 4 sizes: " + ", ".join(f"{w}x{h}" for w, h in TABLE4))
    p.add_argument("--width", type=int, default=24000, help="pixels (default 24000)")
    p.add_argument("--height", type=int, default=1000, help="pixels (default 1000)")
    p.add_argument("--seed", type=int, default=0, help="variation of the landscape (default 0)")
    p.add_argument("--compression", default="none", choices=["none", "zip", "lzw"],
                   help="TIFF compression (default none)")
    p.add_argument("-o", "--output", required=True, help="output .tif file")
    p.add_argument("--force", action="store_true", help="overwrite an existing file")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..pack import synth_painting
    out = Path(args.output)
    if out.exists() and not args.force:
        raise UserError(f"{out}: already exists (use --force to overwrite)")
    if out.suffix.lower() not in (".tif", ".tiff"):
        raise UserError(f"{out}: the output must be a .tif file (tiled BigTIFF)")
    if args.seed < 0:
        raise UserError("--seed must be >= 0")
    synth_painting(out, args.width, args.height, seed=args.seed, compression=args.compression,
                   progress=True)
    print(f"wrote {out} ({args.width} x {args.height}, seed {args.seed})")
    return 0
