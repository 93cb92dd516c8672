"""Reading packs back: the manifest, whole mip levels, checksum verification and a
human-readable summary."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .._core import TilePack
from ..errors import expect_type
from .reader import PurePack

__all__ = ["pack_manifest", "read_level", "verify_pack", "pack_summary"]


def pack_manifest(path) -> dict:
    """The manifest of a pack as a dict, as the core's reader parsed it when opening the pack."""
    return json.loads(TilePack(path).manifest_json())


def read_level(pack: TilePack, painting: int, level: int) -> np.ndarray:
    """Assembles one whole mip level (height, width, 3) from the payloads of its tiles."""
    expect_type(pack, (TilePack, PurePack), "read_level: pack")
    p = pack.paintings[painting]
    if not 0 <= level < p.levels:
        raise ValueError(f"level {level} out of range (painting has {p.levels})")
    w, h = p.level_sizes[level]
    nx, ny = p.level_tiles[level]
    b, P = pack.border, pack.payload
    out = np.empty((h, w, 3), np.uint8)
    for ty in range(ny):
        for tx in range(nx):
            t = pack.read_tile(painting, level, tx, ty)
            ph, pw = min(P, h - ty * P), min(P, w - tx * P)
            out[ty * P:ty * P + ph, tx * P:tx * P + pw] = t[b:b + ph, b:b + pw]
    return out


def verify_pack(pack: TilePack, progress: bool = False) -> int:
    """Reads every stored tile, verifying its checksum; returns the number of tiles read.
    Raises OSError on the first corrupt tile. An instance's tiles are its source's: read
    once, through the source."""
    expect_type(pack, (TilePack, PurePack), "verify_pack: pack")
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=pack.tile_count, unit="tile", desc="verify")
    out = np.empty((pack.tile_size, pack.tile_size, 3), np.uint8)
    n = 0
    for i, p in enumerate(pack.paintings):
        if getattr(p, "instance_of", None) is not None:
            continue
        for l, (nx, ny) in enumerate(p.level_tiles):
            for ty in range(ny):
                for tx in range(nx):
                    pack.read_tile_into(i, l, tx, ty, out)
                    n += 1
            if bar is not None:
                bar.update(nx * ny)
    if bar is not None:
        bar.close()
    return n


def pack_summary(pack: TilePack) -> str:
    """A human-readable summary of a pack: geometry, layout and paintings."""
    expect_type(pack, (TilePack, PurePack), "pack_summary: pack")
    m = pack_manifest(pack.path)
    pt = m["page_table"]
    size = sum(f.stat().st_size for f in Path(pack.path).iterdir() if f.is_file())
    lines = [
        f"tile pack {pack.path}",
        f"  format {m['format']} v{m['version']}, codec {pack.codec}, tile {pack.tile_size} px "
        f"(border {pack.border}, payload {pack.payload}), {pack.tile_count} tiles, "
        f"{size / 2**20:.1f} MiB",
        f"  merged page table {pack.table_size[0]} x {pack.table_size[1]}"
        + (f", packer {pt['packer']}" if "packer" in pt else "")
        + (f", fill {pt['fill_ratio']:.3f}" if "fill_ratio" in pt else "")
        + (f" (shelf {pt['shelf_fill_ratio']:.3f}, BRKGA {pt['brkga_fill_ratio']:.3f})"
           if "shelf_fill_ratio" in pt and "brkga_fill_ratio" in pt else ""),
    ]
    for i, p in enumerate(pack.paintings):
        lines.append(
            f"  [{i}] {p.name}: {p.width} x {p.height}, {p.levels} levels, {p.tile_count} tiles, "
            f"page table {p.table_size[0]} x {p.table_size[1]} at {p.table_offset}, "
            f"uv scale ({p.uv_scale[0]:.6f}, {p.uv_scale[1]:.6f})")
        src = getattr(p, "instance_of", None)
        lines.append(f"      source {p.source}; conversion: {p.conversion}" if src is None else
                     f"      an instance of [{src}] {pack.paintings[src].name}: its tiles, "
                     "stored once")
    return "\n".join(lines)
