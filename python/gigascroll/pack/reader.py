"""A pure-Python tile-pack reader (numpy, xxhash, zstandard, jsonschema) for tools that
cannot load the C++ core. It applies the same checks as the core's reader
(cpp/pack/manifest.cpp, reader.cpp): the manifest against the JSON Schema
(manifest.schema.json, with exact integer types) and the same arithmetic rules, the binaries'
magic, version and sizes on open, and on every read the entry's flags, file and bounds and its
XXH3-64 checksum, which in format version 2 is seeded with the tile's key so that swapped or
duplicated index entries fail. Version 1 packs are read with a warning."""

from __future__ import annotations

import bisect
import json
import math
import os
import re
import stat
import struct
import warnings
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

__all__ = ["PurePack", "PurePainting", "manifest_schema", "validate_manifest",
           "parse_manifest_text", "validate_colour_record", "tile_key", "tile_seed",
           "SCHEMA_PATH", "decode_bc1"]

SCHEMA_PATH = Path(__file__).with_name("manifest.schema.json")
_HEADER = struct.Struct("<8sIIQQ")  # magic, version, entry size, count, data bytes
_TILES_MAGIC, _INDEX_MAGIC = b"GSTILES\0", b"GSINDEX\0"
# Version 2; in version 1 the (flags, file) pair is one u32 of flags whose high half is 0.
_ENTRY = np.dtype([("offset", "<u8"), ("length", "<u4"), ("flags", "<u2"), ("file", "<u2"),
                   ("checksum", "<u8")])
_STORED = 1
PACK_VERSION, OLDEST_PACK_VERSION = 2, 1
MAX_PACK_PAINTINGS = 1 << 16  # the 16-bit painting field of a tile key
MAX_TABLE_SLACK = 16          # merged table area / the smallest area that holds the tables
_TILE_FILE = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9._-]{0,254}")
MAX_JSON_DEPTH = 32           # containers around any value (the core's parse_bounded)
_SURROGATE = re.compile("[\ud800-\udfff]")
_BOM = b"\xef\xbb\xbf"


TILE_SEED_SALT = 0x9E3779B97F4A7C15


def tile_key(p: int, l: int, tx: int, ty: int) -> int:
    """TileKey::packed(): p << 48 | l << 40 | ty << 20 | tx."""
    return (p << 48) | (l << 40) | (ty << 20) | tx


def tile_seed(p: int, l: int, tx: int, ty: int) -> int:
    """The XXH3-64 seed of a version-2 tile's checksum: its key XOR TILE_SEED_SALT."""
    return tile_key(p, l, tx, ty) ^ TILE_SEED_SALT


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


def _is_json_integer(_, v) -> bool:
    """An integer as the core reads one: a JSON integer literal that fits int64 or uint64
    (JSON Schema's "integer" accepts 128.0, and Python's ints are unbounded; the core parses
    a larger literal as a double, so it is a number but not an integer there)."""
    return isinstance(v, int) and not isinstance(v, bool) and -(1 << 63) <= v < (1 << 64)


def _pattern(validator, pattern, instance, schema):
    """ECMA-262's "pattern" (JSON Schema's): `$` matches only at the end; Python's `$` also
    matches before a final newline, which would let "name\n" through."""
    import jsonschema
    if validator.is_type(instance, "string") and \
            not re.search(re.sub(r"(?<!\\)\$$", r"\\Z", pattern), instance):
        yield jsonschema.ValidationError(f"{instance!r} does not match {pattern!r}")


@lru_cache(maxsize=2)
def _validator(definition: str | None = None):
    """Draft 2020-12 with the core's integers and ECMA-262 patterns, for the manifest or
    for one of the schema's $defs."""
    import jsonschema
    base = jsonschema.Draft202012Validator
    checker = base.TYPE_CHECKER.redefine("integer", _is_json_integer)
    schema = manifest_schema()
    if definition is not None:
        schema = {"$schema": schema["$schema"], "$defs": schema["$defs"],
                  "$ref": f"#/$defs/{definition}"}
    return jsonschema.validators.extend(base, validators={"pattern": _pattern},
                                        type_checker=checker)(schema)


def validate_colour_record(colour, where: str = "colour") -> None:
    """A painting's colour record (the schema's $defs/colour) as both readers check it in a
    manifest: OSError naming `where` if not."""
    import jsonschema
    _check_json_values(colour, where)
    try:
        _validator("colour").validate(colour)
    except jsonschema.ValidationError as e:
        path = "/".join(str(p) for p in e.absolute_path) or "(top level)"
        raise OSError(f"{where}: does not match the schema's colour record at {path}: "
                      f"{e.message[:200]}") from None


def _json_value_problem(node, depth: int) -> str | None:
    """Why one value of a parsed manifest could not be in JSON text the core accepts."""
    if depth > MAX_JSON_DEPTH:
        return f"JSON nested deeper than {MAX_JSON_DEPTH} levels"
    if isinstance(node, float) and not math.isfinite(node):
        return f"{node} (JSON has no NaN or Infinity, and a number must fit a double)"
    if isinstance(node, int) and not -(1 << 64) < node < (1 << 64):
        try:
            float(node)
        except OverflowError:
            return "a number beyond a double's range"
    if isinstance(node, str) and (c := _SURROGATE.search(node)):
        return f"a lone surrogate U+{ord(c[0]):04X} in a string (not valid Unicode)"
    if isinstance(node, dict) and any(_SURROGATE.search(k) for k in node if isinstance(k, str)):
        return "a lone surrogate in a key (not valid Unicode)"
    return None


def _check_json_values(m, where: str) -> None:
    """What JSON text can hold, as the core's parser (nlohmann) reads it: no NaN or Infinity,
    no number beyond a double's range, no lone surrogate in a string or key, at most
    MAX_JSON_DEPTH containers around any value. A manifest parsed by Python's json may hold
    all of these; the schema does not see them."""
    stack = [(m, 0, ())]
    while stack:
        node, depth, path = stack.pop()
        if (why := _json_value_problem(node, depth)) is not None:
            at = "/".join(map(str, path)) or "(top level)"
            raise OSError(f"{where}: {why} at {at[:200]}")
        if isinstance(node, dict):
            stack.extend((v, depth + 1, path + (k,)) for k, v in node.items())
        elif isinstance(node, list):
            stack.extend((v, depth + 1, path + (i,)) for i, v in enumerate(node))


def parse_manifest_text(data: bytes | str, where: str = "manifest.json") -> dict:
    """manifest.json's bytes (or text) -> the validated manifest, with the core's rules
    (cpp/pack/manifest.cpp): JSON text of RFC 8259 in UTF-8 without a byte-order mark, then
    validate_manifest(). OSError naming `where` if not."""
    if isinstance(data, (bytes, bytearray, memoryview)):
        data = bytes(data)
        if data.startswith(_BOM):
            raise OSError(f"{where}: a byte-order mark before the JSON text (JSON allows none)")
        try:
            data = data.decode("utf-8")
        except UnicodeDecodeError as e:
            raise OSError(f"{where}: corrupt manifest: not UTF-8 ({e.reason} at byte "
                          f"{e.start})") from None
    if data.startswith("\ufeff"):
        raise OSError(f"{where}: a byte-order mark before the JSON text (JSON allows none)")
    try:
        m = json.loads(data)
    except (ValueError, RecursionError) as e:  # JSONDecodeError; ints of > 4300 digits
        raise OSError(f"{where}: corrupt manifest: {str(e)[:200]}") from None
    validate_manifest(m, where)
    return m


def _check_disjoint(m: dict, where: str) -> None:
    """Page tables pairwise disjoint, by a sweep over x (the core's check_disjoint)."""
    events = []
    for i, p in enumerate(m["paintings"]):
        pt = p["page_table"]
        events.append((pt["x"], 1, i))
        events.append((pt["x"] + pt["width"], 0, i))  # closings sort before openings
    events.sort()
    ys: list[int] = []       # sorted y0 of the tables crossing the sweep line
    owner: dict[int, int] = {}
    for _, opening, i in events:
        pt = m["paintings"][i]["page_table"]
        y0, y1 = pt["y"], pt["y"] + pt["height"]
        if not opening:
            ys.pop(bisect.bisect_left(ys, y0))
            del owner[y0]
            continue
        k = bisect.bisect_left(ys, y0)
        clash = None
        if k < len(ys) and ys[k] < y1:
            clash = owner[ys[k]]
        elif k > 0:
            q = m["paintings"][owner[ys[k - 1]]]["page_table"]
            if q["y"] + q["height"] > y0:
                clash = owner[ys[k - 1]]
        if clash is not None:
            raise OSError(f"{where}: page tables of paintings[{clash}] "
                          f"('{m['paintings'][clash]['name']}') and paintings[{i}] "
                          f"('{m['paintings'][i]['name']}') overlap")
        ys.insert(k, y0)
        owner[y0] = i


def _check_instance(m: dict, i: int, where: str) -> dict | None:
    """The source painting of painting i if it is an instance (None if it stores its own
    tiles): an earlier painting, itself no instance, of the same size; version 2 and later."""
    p = m["paintings"][i]
    if "instance_of" not in p:
        return None
    s = p["instance_of"]
    field = f"field 'paintings[{i}].instance_of'"
    if m["version"] < 2:
        raise OSError(f"{where}: {field}: a version-1 pack has no instances")
    if s >= i:
        raise OSError(f"{where}: {field} = {s} must name an earlier painting")
    src = m["paintings"][s]
    if "instance_of" in src:
        raise OSError(f"{where}: {field}: paintings[{s}] is itself an instance")
    if (p["width"], p["height"]) != (src["width"], src["height"]):
        raise OSError(f"{where}: paintings[{i}] ('{p['name']}'): {p['width']} x {p['height']} "
                      f"differs from its source's {src['width']} x {src['height']}")
    return src


def validate_manifest(m: dict, where: str = "manifest.json") -> None:
    """Checks a parsed manifest as the core does: the schema with exact integer types, then
    its arithmetic (level sizes, tile grids, running entry totals, page-table sizes,
    placements, overlap, the merged table's size, uv scales). OSError naming `where` and the
    field if not."""
    import jsonschema
    _check_json_values(m, where)
    if isinstance(m, dict) and isinstance(m.get("version"), int) and \
            not isinstance(m["version"], bool) and m["version"] not in (1, 2):
        raise OSError(f"{where}: unsupported pack version {m['version']} (this reader reads 1 to 2)")
    try:
        _validator().validate(m)
    except jsonschema.ValidationError as e:
        path = "/".join(str(p) for p in e.absolute_path) or "(top level)"
        raise OSError(f"{where}: manifest does not match the schema at {path}: "
                      f"{e.message[:200]}") from None
    T, b = m["tile_size"], m["border"]
    if T <= 2 * b or m["payload"] != T - 2 * b:
        raise OSError(f"{where}: tile_size {T}, border {b} and payload {m['payload']} disagree")
    if m["codec"] == "bc1" and (T % 4 or (T - 2 * b) % 4):
        raise OSError(f"{where}: a bc1 pack needs tile_size and payload that are multiples of 4")
    P = T - 2 * b
    Mc, Nc = m["page_table"]["width"], m["page_table"]["height"]
    entries = area = wmax = hmax = 0
    for i, p in enumerate(m["paintings"]):
        name = p["name"]
        levels = _expected_levels(p["width"], p["height"], P)
        pt = p["page_table"]
        src = _check_instance(m, i, where)
        if (len(p["levels"]) != len(levels) or p["first_entry"] != (entries if src is None
                                                                     else src["first_entry"])
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
        u, v = p["uv_scale"]
        eu, ev = p["width"] / (pt["width"] * P), p["height"] / (pt["height"] * P)
        if not (abs(u - eu) <= 1e-9 * eu and abs(v - ev) <= 1e-9 * ev):
            raise OSError(f"{where}: field 'paintings[{i}].uv_scale' does not match the "
                          "painting's size")
        entries += first if src is None else 0  # an instance's tiles are its source's
        area += pt["width"] * pt["height"]
        wmax, hmax = max(wmax, pt["width"]), max(hmax, pt["height"])
    if m["tile_count"] != entries:
        raise OSError(f"{where}: tile_count does not match the paintings")
    need = max(_next_pow2(area), wmax * hmax)
    if Mc * Nc > MAX_TABLE_SLACK * need:
        raise OSError(f"{where}: field 'page_table': the merged {Mc} x {Nc} table is absurdly "
                      f"large for paintings whose tables need {need} entries")
    _check_disjoint(m, where)
    for i, f in enumerate(m.get("tile_files", ())):
        if not _TILE_FILE.fullmatch(f):  # the schema's pattern lets "name\n" through
            raise OSError(f"{where}: field 'tile_files[{i}]' is not a plain tile file name")


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
    instance_of: int | None = None  # the painting whose stored tiles this one reads

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
        self._fds: list[int] = []
        d = Path(path)
        mpath = d / "manifest.json"
        for f in (mpath, d / "index.bin"):
            _require_regular_file(f)
        if mpath.stat().st_size > 256 << 20:
            raise OSError(f"{mpath}: manifest too large")
        try:
            text = mpath.read_bytes()
        except FileNotFoundError:
            raise OSError(f"{mpath}: missing manifest (not a finished tile pack)") from None
        m = parse_manifest_text(text, str(mpath))
        self.manifest = m
        self.version = m["version"]
        if self.version < 2:
            warnings.warn(f"{self.path}: a version-1 pack: its checksums do not name their tiles, "
                          "so swapped or duplicated index entries cannot be detected (rebuild it "
                          "to get version 2)", UserWarning, stacklevel=2)
        self.tile_size, self.border, self.payload = m["tile_size"], m["border"], m["payload"]
        self.codec = m["codec"]
        self.table_size = (m["page_table"]["width"], m["page_table"]["height"])
        self.tile_count = m["tile_count"]
        self.tile_files = list(m.get("tile_files", ["tiles.bin"]))
        self.paintings = [PurePainting(
            p["name"], p.get("source", ""), p.get("conversion", ""), p.get("colour"),
            p["width"], p["height"], p["first_entry"],
            [(lv["width"], lv["height"]) for lv in p["levels"]],
            [(lv["tiles_x"], lv["tiles_y"]) for lv in p["levels"]],
            [lv["first_entry"] for lv in p["levels"]],
            (p["page_table"]["width"], p["page_table"]["height"]),
            (p["page_table"]["x"], p["page_table"]["y"]), p.get("instance_of"))
            for p in m["paintings"]]

        ipath = d / "index.bin"
        size = ipath.stat().st_size
        if size != _HEADER.size + self.tile_count * _ENTRY.itemsize:
            # Checked before reading: a hostile manifest cannot make us read a huge file.
            raise OSError(f"{ipath}: truncated or inconsistent index ({size} bytes for "
                          f"{self.tile_count} tiles)")
        raw = self._read_all(ipath)
        self._check_header(raw, _INDEX_MAGIC, ipath)
        _, _, entry_size, count, data_bytes = _HEADER.unpack_from(raw)
        if (entry_size != _ENTRY.itemsize or count != self.tile_count
                or data_bytes != count * _ENTRY.itemsize or len(raw) != _HEADER.size + data_bytes):
            raise OSError(f"{ipath}: truncated or inconsistent index ({len(raw)} bytes for "
                          f"{self.tile_count} tiles)")
        self._entries = np.frombuffer(raw, _ENTRY, count, _HEADER.size)

        self._sizes: list[int] = []
        try:
            tiles = total = 0
            for name in self.tile_files:
                tpath = d / name
                _require_regular_file(tpath)
                try:
                    fd = os.open(tpath, os.O_RDONLY | getattr(os, "O_CLOEXEC", 0))
                except OSError as e:
                    raise OSError(f"{tpath}: cannot open: {e.strerror}") from None
                self._fds.append(fd)
                fsize = os.fstat(fd).st_size
                head = os.pread(fd, _HEADER.size, 0)
                self._check_header(head, _TILES_MAGIC, tpath)
                _, _, _, tcount, tbytes = _HEADER.unpack_from(head)
                if fsize != _HEADER.size + tbytes or tcount > self.tile_count:
                    raise OSError(f"{tpath}: truncated tile data ({fsize} bytes, header "
                                  f"promises {_HEADER.size + tbytes})")
                self._sizes.append(fsize)
                tiles += tcount
                total += fsize
            if tiles != self.tile_count:
                raise OSError(f"{self.path}: the tile files hold {tiles} tiles, the manifest "
                              f"{self.tile_count}")
            if (self.version >= 2 or m.get("tiles_bytes", 0)) and total != m["tiles_bytes"]:
                raise OSError(f"{self.path}: the tile files hold {total} bytes, the manifest's "
                              f"tiles_bytes says {m['tiles_bytes']}")
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

    def _check_header(self, raw: bytes, magic: bytes, path: Path) -> None:
        if len(raw) < _HEADER.size:
            raise OSError(f"{path}: truncated file")
        got, version = _HEADER.unpack_from(raw)[:2]
        if got != magic:
            raise OSError(f"{path}: not a gigascroll pack file (wrong magic)")
        if version != self.version:
            raise OSError(f"{path}: unsupported pack version {version} (the manifest says "
                          f"version {self.version})")

    def close(self) -> None:
        for fd in getattr(self, "_fds", ()):
            os.close(fd)
        self._fds = []

    def __enter__(self) -> "PurePack":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self):
        self.close()

    def _painting_index(self, p) -> int:
        """`p` as an index, as TilePack takes it: a painting of this pack (an object of
        `self.paintings`) or its index. ValueError for another pack's painting."""
        if not isinstance(p, PurePainting):
            return p
        if getattr(self, "_painting_ids", None) is None:
            self._painting_ids = {id(q): i for i, q in enumerate(self.paintings)}
        i = self._painting_ids.get(id(p))
        if i is None or self.paintings[i] is not p:
            raise ValueError(f"painting {p.name!r} is not one of this pack's paintings (pass "
                             "pack.paintings[i] of this pack, or the index i)")
        return i

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

    def _entry(self, p: int, l: int, tx: int, ty: int):
        """The checked entry: flags exactly "stored", a listed file, inside that file."""
        key = f"(painting {p}, level {l}, tile {tx}, {ty})"
        e = self._entries[self._entry_index(p, l, tx, ty)]
        flags, file = int(e["flags"]), int(e["file"])
        if flags != _STORED or (self.version < 2 and file != 0):
            shown = (file << 16 | flags) if self.version < 2 else flags
            raise OSError(f"{self.path}: index entry of tile {key} has flags {shown:#x} (a "
                          "finished pack stores only 1 = stored)")
        if file >= len(self.tile_files):
            raise OSError(f"{self.path}: index entry of tile {key} names tile file {file} of "
                          f"{len(self.tile_files)}")
        offset, length, size = int(e["offset"]), int(e["length"]), self._sizes[file]
        if offset < _HEADER.size or offset + length > size:
            raise OSError(f"{self.path}: index entry of tile {key} points outside "
                          f"{self.tile_files[file]}")
        return key, file, offset, length, int(e["checksum"])

    def locate(self, p: int, l: int, tx: int, ty: int) -> tuple[int, int, int]:
        """(offset, length, checksum) of a stored tile in its tile file."""
        p = self._painting_index(p)
        _, _, offset, length, checksum = self._entry(p, l, tx, ty)
        return offset, length, checksum

    def tile_file(self, p: int, l: int, tx: int, ty: int) -> str:
        """Name of the tile file that holds the tile."""
        p = self._painting_index(p)
        return self.tile_files[self._entry(p, l, tx, ty)[1]]

    def read_tile(self, p: int, l: int, tx: int, ty: int) -> np.ndarray:
        """Reads, decompresses and verifies one tile: (tile_size, tile_size, 3) uint8. The
        painting is the object in `paintings` or its index."""
        import xxhash
        p = self._painting_index(p)
        key, file, offset, length, checksum = self._entry(p, l, tx, ty)
        nbytes = self.tile_size * self.tile_size * 3
        if self.codec == "bc1":
            nbytes = self.tile_size * self.tile_size // 2
        if self._zstd is None and length != nbytes:
            raise OSError(f"{self.path}: tile {key} has length {length}, expected {nbytes}")
        data = os.pread(self._fds[file], length, offset)
        if len(data) != length:
            raise OSError(f"{self.path}: short read of tile {key}")
        source = self.paintings[p].instance_of  # an instance's checksums name its source's tiles
        seed = tile_seed(p if source is None else source, l, tx, ty) if self.version >= 2 else 0
        if xxhash.xxh3_64_intdigest(data, seed=seed) != checksum:
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
