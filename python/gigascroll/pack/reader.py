"""A pure-Python tile-pack reader (numpy, xxhash, zstandard, jsonschema) for tools that
cannot load the C++ core. It applies the same checks as the core's reader: the manifest
against the JSON Schema (manifest.schema.json) and its geometry arithmetic, the binaries'
magic, version and sizes on open, and the XXH3-64 checksum of every tile read."""

from __future__ import annotations

import json
import os
import stat
import struct
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

__all__ = ["PurePack", "PurePainting", "manifest_schema", "validate_manifest", "SCHEMA_PATH",
           "decode_bc1"]

SCHEMA_PATH = Path(__file__).with_name("manifest.schema.json")
_HEADER = struct.Struct("<8sIIQQ")  # magic, version, entry size, count, data bytes
_TILES_MAGIC, _INDEX_MAGIC = b"GSTILES\0", b"GSINDEX\0"
_ENTRY = np.dtype([("offset", "<u8"), ("length", "<u4"), ("flags", "<u4"), ("checksum", "<u8")])
_STORED = 1


def decode_bc1(blocks: np.ndarray) -> np.ndarray:
    """(by, bx, 8) uint8 BC1 blocks -> (4 by, 4 bx, 3) uint8 RGB, with the core's (and
    libsquish's) arithmetic: endpoints widened by bit replication, thirds or halves by integer
    division, black for index 3 of a block whose c0 <= c1."""
    b = np.asarray(blocks, np.uint8)
    by, bx = b.shape[:2]
    c = b[..., :4].astype(np.uint32)
    c0, c1 = c[..., 0] | c[..., 1] << 8, c[..., 2] | c[..., 3] << 8
    def widen(v):
        r, g, bl = v >> 11, (v >> 5) & 63, v & 31
        return np.stack([r << 3 | r >> 2, g << 2 | g >> 4, bl << 3 | bl >> 2], -1)
    a, e = widen(c0), widen(c1)
    four = (c0 > c1)[..., None]
    palette = np.stack([a, e, np.where(four, (2 * a + e) // 3, (a + e) // 2),
                        np.where(four, (a + 2 * e) // 3, 0)], -2)  # (by, bx, 4, 3)
    rows = b[..., 4:8].astype(np.uint32)  # (by, bx, 4 rows)
    idx = (rows[..., :, None] >> (2 * np.arange(4, dtype=np.uint32))) & 3  # (by, bx, 4, 4)
    texels = np.take_along_axis(palette, idx.reshape(by, bx, 16, 1), axis=2)  # (by, bx, 16, 3)
    out = texels.reshape(by, bx, 4, 4, 3).transpose(0, 2, 1, 3, 4).reshape(4 * by, 4 * bx, 3)
    return out.astype(np.uint8)


@lru_cache(maxsize=1)
def manifest_schema() -> dict:
    """The JSON Schema of manifest.json (draft 2020-12)."""
    return json.loads(SCHEMA_PATH.read_text())


def _expected_levels(width: int, height: int, payload: int) -> list[tuple[int, int, int, int]]:
    """(width, height, tiles_x, tiles_y) of every mip level, as the core computes them."""
    out, l = [], 0
    while True:
        w, h = -(-width // (1 << l)), -(-height // (1 << l))
        out.append((w, h, -(-w // payload), -(-h // payload)))
        if w <= payload and h <= payload:
            return out
        l += 1


def _next_pow2(n: int) -> int:
    return 1 << max(0, (n - 1).bit_length())


def validate_manifest(m: dict, where: str = "manifest.json") -> None:
    """Checks a parsed manifest against the schema and its arithmetic (level sizes, tile grids,
    running entry totals, page-table sizes and placements). OSError naming `where` if not."""
    import jsonschema
    try:
        jsonschema.validate(m, manifest_schema(), cls=jsonschema.Draft202012Validator)
    except jsonschema.ValidationError as e:
        path = "/".join(str(p) for p in e.absolute_path) or "(top level)"
        raise OSError(f"{where}: manifest does not match the schema at {path}: {e.message}") from None
    T, b = m["tile_size"], m["border"]
    if T <= 2 * b or m["payload"] != T - 2 * b:
        raise OSError(f"{where}: tile_size {T}, border {b} and payload {m['payload']} disagree")
    if m["codec"] == "bc1" and (T % 4 or (T - 2 * b) % 4):
        raise OSError(f"{where}: a bc1 pack needs tile_size and payload that are multiples of 4")
    P = T - 2 * b
    Mc, Nc = m["page_table"]["width"], m["page_table"]["height"]
    entries = 0
    for p in m["paintings"]:
        name = p["name"]
        levels = _expected_levels(p["width"], p["height"], P)
        pt = p["page_table"]
        if (len(p["levels"]) != len(levels) or p["first_entry"] != entries
                or pt["width"] != _next_pow2(levels[0][2]) or pt["height"] != _next_pow2(levels[0][3])):
            raise OSError(f"{where}: geometry of painting '{name}' does not match its size")
        if (pt["x"] % pt["width"] or pt["y"] % pt["height"] or pt["x"] + pt["width"] > Mc
                or pt["y"] + pt["height"] > Nc):
            raise OSError(f"{where}: page-table offset of painting '{name}' is unaligned or "
                          "outside the merged table")
        first = 0
        for i, (lv, (w, h, nx, ny)) in enumerate(zip(p["levels"], levels)):
            if (lv["level"], lv["width"], lv["height"], lv["tiles_x"], lv["tiles_y"],
                    lv["first_entry"]) != (i, w, h, nx, ny, first):
                raise OSError(f"{where}: level {i} of painting '{name}' does not match its size")
            first += nx * ny
        if p["tile_count"] != first:
            raise OSError(f"{where}: tile_count of painting '{name}' does not match its levels")
        entries += first
    if m["tile_count"] != entries:
        raise OSError(f"{where}: tile_count does not match the paintings")


@dataclass(frozen=True)
class PurePainting:
    """One painting of a pack, as the manifest describes it."""
    name: str
    source: str
    conversion: str
    colour: dict | None
    width: int
    height: int
    first_entry: int
    level_sizes: list[tuple[int, int]]
    level_tiles: list[tuple[int, int]]
    level_first: list[int]
    table_size: tuple[int, int]
    table_offset: tuple[int, int]

    @property
    def levels(self) -> int:
        return len(self.level_sizes)

    @property
    def tile_count(self) -> int:
        return sum(nx * ny for nx, ny in self.level_tiles)


def _require_regular_file(path: Path) -> None:
    """A FIFO or device in a pack file's place would block open() or read() forever."""
    try:
        st = path.stat()
    except FileNotFoundError:
        if path.name == "manifest.json":
            raise OSError(f"{path}: missing manifest (not a finished tile pack)") from None
        raise OSError(f"{path}: cannot open: no such file") from None
    if not stat.S_ISREG(st.st_mode):
        raise OSError(f"{path}: not a regular file")


class PurePack:
    """A tile pack opened for reading without the core. read_tile returns a
    (tile_size, tile_size, 3) uint8 array like gigascroll.TilePack.read_tile."""

    def __init__(self, path: str | os.PathLike):
        self.path = str(path)
        d = Path(path)
        mpath = d / "manifest.json"
        for f in (mpath, d / "index.bin", d / "tiles.bin"):
            _require_regular_file(f)
        try:
            text = mpath.read_text()
        except FileNotFoundError:
            raise OSError(f"{mpath}: missing manifest (not a finished tile pack)") from None
        try:
            m = json.loads(text)
        except json.JSONDecodeError as e:
            raise OSError(f"{mpath}: corrupt manifest: {e}") from None
        validate_manifest(m, str(mpath))
        self.manifest = m
        self.tile_size, self.border, self.payload = m["tile_size"], m["border"], m["payload"]
        self.codec = m["codec"]
        self.table_size = (m["page_table"]["width"], m["page_table"]["height"])
        self.tile_count = m["tile_count"]
        self.paintings = [PurePainting(
            p["name"], p.get("source", ""), p.get("conversion", ""), p.get("colour"),
            p["width"], p["height"], p["first_entry"],
            [(lv["width"], lv["height"]) for lv in p["levels"]],
            [(lv["tiles_x"], lv["tiles_y"]) for lv in p["levels"]],
            [lv["first_entry"] for lv in p["levels"]],
            (p["page_table"]["width"], p["page_table"]["height"]),
            (p["page_table"]["x"], p["page_table"]["y"])) for p in m["paintings"]]

        ipath = d / "index.bin"
        raw = self._read_all(ipath)
        self._check_header(raw, _INDEX_MAGIC, ipath)
        _, _, entry_size, count, data_bytes = _HEADER.unpack_from(raw)
        if (entry_size != _ENTRY.itemsize or count != self.tile_count
                or data_bytes != count * _ENTRY.itemsize or len(raw) != _HEADER.size + data_bytes):
            raise OSError(f"{ipath}: truncated or inconsistent index ({len(raw)} bytes for "
                          f"{self.tile_count} tiles)")
        self._entries = np.frombuffer(raw, _ENTRY, count, _HEADER.size)

        tpath = d / "tiles.bin"
        self._tiles_path = tpath
        try:
            self._fd = os.open(tpath, os.O_RDONLY | getattr(os, "O_CLOEXEC", 0))
        except OSError as e:
            raise OSError(f"{tpath}: cannot open: {e.strerror}") from None
        try:
            self._tiles_size = os.fstat(self._fd).st_size
            head = os.pread(self._fd, _HEADER.size, 0)
            self._check_header(head, _TILES_MAGIC, tpath)
            _, _, _, tcount, tbytes = _HEADER.unpack_from(head)
            if self._tiles_size != _HEADER.size + tbytes or tcount != self.tile_count:
                raise OSError(f"{tpath}: truncated tile data ({self._tiles_size} bytes, header "
                              f"promises {_HEADER.size + tbytes})")
        except BaseException:
            self.close()
            raise
        self._zstd = None
        if self.codec == "zstd":
            import zstandard
            self._zstd = zstandard.ZstdDecompressor()

    @staticmethod
    def _read_all(path: Path) -> bytes:
        try:
            return path.read_bytes()
        except OSError as e:
            raise OSError(f"{path}: cannot open: {e.strerror}") from None

    @staticmethod
    def _check_header(raw: bytes, magic: bytes, path: Path) -> None:
        if len(raw) < _HEADER.size:
            raise OSError(f"{path}: truncated file")
        got, version = _HEADER.unpack_from(raw)[:2]
        if got != magic:
            raise OSError(f"{path}: not a gigascroll pack file (wrong magic)")
        if version != 1:
            raise OSError(f"{path}: unsupported pack version {version} (this reader reads 1)")

    def close(self) -> None:
        if getattr(self, "_fd", -1) >= 0:
            os.close(self._fd)
            self._fd = -1

    def __enter__(self) -> "PurePack":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self):
        self.close()

    def _entry_index(self, p: int, l: int, tx: int, ty: int) -> int:
        if not 0 <= p < len(self.paintings):
            raise ValueError(f"painting {p} out of range (pack has {len(self.paintings)})")
        pp = self.paintings[p]
        if not 0 <= l < pp.levels:
            raise ValueError(f"level {l} out of range (painting {p} has {pp.levels})")
        nx, ny = pp.level_tiles[l]
        if not (0 <= tx < nx and 0 <= ty < ny):
            raise ValueError(f"tile (painting {p}, level {l}, tile {tx}, {ty}) is not stored "
                             f"(the level has {nx} x {ny} tiles)")
        return pp.first_entry + pp.level_first[l] + ty * nx + tx

    def locate(self, p: int, l: int, tx: int, ty: int) -> tuple[int, int, int]:
        """(offset, length, checksum) of a stored tile in tiles.bin."""
        e = self._entries[self._entry_index(p, l, tx, ty)]
        return int(e["offset"]), int(e["length"]), int(e["checksum"])

    def read_tile(self, p: int, l: int, tx: int, ty: int) -> np.ndarray:
        """Reads, decompresses and verifies one tile: (tile_size, tile_size, 3) uint8."""
        import xxhash
        key = f"(painting {p}, level {l}, tile {tx}, {ty})"
        e = self._entries[self._entry_index(p, l, tx, ty)]
        offset, length = int(e["offset"]), int(e["length"])
        if not e["flags"] & _STORED:
            raise OSError(f"{self.path}: tile {key} is a hole (not stored)")
        if offset < _HEADER.size or offset + length > self._tiles_size:
            raise OSError(f"{self.path}: index entry of tile {key} points outside tiles.bin")
        nbytes = self.tile_size * self.tile_size * 3
        if self.codec == "bc1":
            nbytes = self.tile_size * self.tile_size // 2
        if self._zstd is None and length != nbytes:
            raise OSError(f"{self.path}: tile {key} has length {length}, expected {nbytes}")
        data = os.pread(self._fd, length, offset)
        if len(data) != length:
            raise OSError(f"{self.path}: short read of tile {key}")
        if xxhash.xxh3_64_intdigest(data) != int(e["checksum"]):
            raise OSError(f"{self.path}: checksum mismatch in tile {key}")
        if self._zstd is not None:
            import zstandard
            try:
                data = self._zstd.decompress(data, max_output_size=nbytes)
            except zstandard.ZstdError as err:
                raise OSError(f"{self.path}: corrupt zstd data in tile {key}: {err}") from None
            if len(data) != nbytes:
                raise OSError(f"{self.path}: corrupt zstd data in tile {key}")
        if self.codec == "bc1":
            n = self.tile_size // 4
            return decode_bc1(np.frombuffer(data, np.uint8).reshape(n, n, 8))
        return np.frombuffer(data, np.uint8).reshape(self.tile_size, self.tile_size, 3).copy()
