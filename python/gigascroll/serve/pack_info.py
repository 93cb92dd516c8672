"""The served pack: its content hash and its description for scene.json.

The content hash names the pack's tiles in URLs (immutable, cacheable forever): a hash of the
manifest and of index.bin, which holds every stored tile's checksum (XXH3 of its bytes, seeded
with its key) and place. It costs reading two small files, never the tiles; a changed tile
changes its checksum, so a rebuilt pack gets new URLs."""

from __future__ import annotations

import hashlib
from pathlib import Path

from .._core import TilePack
from ..errors import expect_type

__all__ = ["pack_hash", "pack_description"]

INDEX_NAME, MANIFEST_NAME = "index.bin", "manifest.json"


def pack_hash(pack) -> str:
    """32 hex digits naming the pack's content (manifest and tile checksums)."""
    root = Path(expect_type(pack, TilePack, "pack").path)
    h = hashlib.blake2b(digest_size=16, person=b"gigascroll-pack")
    for name in (MANIFEST_NAME, INDEX_NAME):
        h.update(name.encode() + b"\0")
        with open(root / name, "rb") as f:
            while chunk := f.read(1 << 20):
                h.update(chunk)
    return h.hexdigest()


def pack_description(pack, content_hash: str) -> dict:
    """scene.json's "pack": geometry, paintings, page-table placement (docs/serve-protocol.md)."""
    expect_type(pack, TilePack, "pack")
    expect_type(content_hash, str, "content_hash")
    return {
        "hash": content_hash, "tile_size": pack.tile_size, "border": pack.border,
        "payload": pack.payload, "table_size": list(pack.table_size),
        "paintings": [
            {"index": k, "name": p.name, "width": p.width, "height": p.height, "levels": p.levels,
             "level_sizes": [list(s) for s in p.level_sizes],
             "level_tiles": [list(t) for t in p.level_tiles],
             "table_size": list(p.table_size), "table_offset": list(p.table_offset),
             "uv_scale": list(p.uv_scale)}
            for k, p in enumerate(pack.paintings)],
    }
