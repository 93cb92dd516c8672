"""One verdict on a pack (issue 43, family 6): the core's reader and the pure-Python one accept
and refuse exactly the same manifest.json bytes, by the rules of the published schema
(manifest.schema.json) and of JSON text (RFC 8259): no NaN or Infinity, no number beyond a
double, no lone surrogate, no byte-order mark, no invalid UTF-8, at most 32 levels of
nesting, no unknown key in a level, colour records as the schema has them. Every mutation is
judged by both readers, on the text (_core.check_manifest against parse_manifest_text) and on
a pack directory (TilePack against PurePack); hypothesis then tries random colour records and
hostile values. A resumed sharded build must not copy an edited shard record into the
manifest: the shard is rebuilt, and both readers accept the result."""

from __future__ import annotations

import copy
import json
import os
import shutil

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gigascroll import TilePack, _core, build_pack
from gigascroll.pack.reader import PurePack, parse_manifest_text

PROFILE = {"description": "Display P3", "sha256": "a" * 64, "bytes": 536, "colour_space": "RGB",
           "class": "mntr"}


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    """A valid two-painting pack (the second 24 x 24: its uv_scale is exactly 1) and its
    manifest, the first painting carrying a colour record with an ICC profile."""
    rng = np.random.default_rng(43)
    a = rng.integers(0, 256, (30, 41, 3), dtype=np.uint8)
    b = rng.integers(0, 256, (24, 24, 3), dtype=np.uint8)
    root = tmp_path_factory.mktemp("round2")
    build_pack([a, b], root / "p", tile_size=16, border=2)
    m = json.loads((root / "p" / "manifest.json").read_text())
    m["paintings"][0]["colour"] = {"mode": "convert", "source_space": "embedded ICC profile",
                                   "profile": dict(PROFILE), "intent": "relative",
                                   "black_point_compensation": True, "stored_space": "sRGB",
                                   "transform": "LittleCMS"}
    assert m["paintings"][1]["uv_scale"] == [1.0, 1.0]
    return root, m


def _outcome(f) -> str:
    try:
        f()
        return "ok"
    except (ValueError, OSError) as e:  # the core's text check raises ValueError
        return f"refuses: {type(e).__name__}: {e}"


def verdicts(data: bytes, pack_dir=None) -> dict[str, str]:
    """'ok' or the refusal of each reader for manifest bytes: the core's and the pure
    reader's text checks, and with `pack_dir` both readers opening a pack whose
    manifest.json holds these bytes (the core's check_manifest takes text, so bytes that
    are not UTF-8 reach the core through the file only)."""
    out = {"pure text": _outcome(lambda: parse_manifest_text(data))}
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        text = None
    if text is not None:
        out["core text"] = _outcome(lambda: _core.check_manifest(text))
    if pack_dir is not None:
        (pack_dir / "manifest.json").write_bytes(data)
        out["core pack"] = _outcome(lambda: TilePack(pack_dir))
        out["pure pack"] = _outcome(lambda: PurePack(pack_dir).close())
    return out


def assert_agree(data: bytes, expect_ok: bool, pack_dir=None) -> None:
    out = verdicts(data, pack_dir)
    assert {v == "ok" for v in out.values()} == {expect_ok}, \
        {k: v[:200] for k, v in out.items()}


def _set(path, value):
    def mutate(m):
        node = m
        for k in path[:-1]:
            node = node[k]
        node[path[-1]] = value
    return mutate


def _drop(path):
    def mutate(m):
        node = m
        for k in path[:-1]:
            node = node[k]
        del node[path[-1]]
    return mutate


C = ("paintings", 0, "colour")
P = C + ("profile",)

# (what, mutation of the parsed manifest, whether both accept it)
STRUCTURE = [
    ("the manifest as built, with a profile", lambda m: None, True),
    ("unknown key in a level", _set(("paintings", 0, "levels", 0, "note"), 1), False),
    ("unknown key in the last level", _set(("paintings", 1, "levels", -1, "x"), None), False),
    ("unknown key in a painting (allowed)", _set(("paintings", 0, "note"), 1), True),
    ("unknown key in page_table (allowed)", _set(("page_table", "note"), [1]), True),
    ("unknown key at the top (allowed)", _set(("note",), {"a": 1}), True),
    ("unknown key in a colour record (allowed)", _set(C + ("note",), 1), True),
    ("colour mode maybe", _set(C + ("mode",), "maybe"), False),
    ("colour without mode", _drop(C + ("mode",)), False),
    ("colour without profile", _drop(C + ("profile",)), False),
    ("colour without transform", _drop(C + ("transform",)), False),
    ("colour source_space unknown", _set(C + ("source_space",), "guess"), False),
    ("colour stored_space unknown", _set(C + ("stored_space",), "linear"), False),
    ("colour transform not a string", _set(C + ("transform",), 0), False),
    ("colour intent null (allowed)", _set(C + ("intent",), None), True),
    ("colour intent unknown", _set(C + ("intent",), "colorimetric"), False),
    ("colour bpc as 1", _set(C + ("black_point_compensation",), 1), False),
    ("colour chromaticities (allowed)", _set(C + ("chromaticities",), [0.6, .3, .3, .6, .1, 0,
                                                                        .3, .3]), True),
    ("colour chromaticities of 7", _set(C + ("chromaticities",), [0.5] * 7), False),
    ("colour chromaticities with a string", _set(C + ("chromaticities",), [0.5] * 7 + ["1"]),
     False),
    ("colour chromaticities with a bool", _set(C + ("chromaticities",), [0.5] * 7 + [True]),
     False),
    ("colour a list", _set(C, [1]), False),
    ("colour null", _set(C, None), False),
    ("profile a string", _set(P, "sRGB"), False),
    ("profile without sha256", _drop(P + ("sha256",)), False),
    ("profile sha256 upper case", _set(P + ("sha256",), "A" * 64), False),
    ("profile sha256 with a newline", _set(P + ("sha256",), "a" * 64 + "\n"), False),
    ("profile sha256 of 63", _set(P + ("sha256",), "a" * 63), False),
    ("profile bytes 127", _set(P + ("bytes",), 127), False),
    ("profile bytes 536.0", _set(P + ("bytes",), 536.0), False),
    ("profile bytes true", _set(P + ("bytes",), True), False),
    ("profile bytes 2^63 (allowed)", _set(P + ("bytes",), 2 ** 63), True),
    ("profile bytes 2^64 - 1 (allowed)", _set(P + ("bytes",), 2 ** 64 - 1), True),
    ("profile bytes 2^64 (a double in the core)", _set(P + ("bytes",), 2 ** 64), False),
    ("profile colour_space LAB", _set(P + ("colour_space",), "LAB"), False),
    ("profile class link", _set(P + ("class",), "link"), False),
    ("profile description null", _set(P + ("description",), None), False),
    ("uv_scale 1 + 1e-10 (within tolerance, above the range)",
     _set(("paintings", 1, "uv_scale", 0), 1 + 1e-10), False),
    ("a huge integer where any value goes", _set(("note",), 10 ** 300), True),
    ("an integer beyond a double", _set(("note",), 10 ** 309), False),
    ("a float underflowing to 0 (allowed)", _set(("note",), 1e-320), True),
    ("lone surrogate in a name", _set(("paintings", 0, "name"), "a\ud800"), False),
    ("lone low surrogate in a source", _set(("paintings", 0, "source"), "\udc00"), False),
    ("lone surrogate in a key", _set(("paintings", 0, "\ud83d"), 1), False),
    ("a surrogate pair in a name (allowed)", _set(("paintings", 0, "name"), "a\U0001F600"), True),
    ("U+FEFF inside a name (allowed)", _set(("paintings", 0, "name"), "\ufeffa"), True),
    ("NUL inside a name (allowed)", _set(("paintings", 0, "name"), "a\0b"), True),
    ("NaN where any value goes", _set(("note",), float("nan")), False),
    ("Infinity as a fill ratio", _set(("page_table", "fill_ratio"), float("inf")), False),
    ("-Infinity in a colour record", _set(C + ("note",), float("-inf")), False),
    ("NaN in chromaticities", _set(C + ("chromaticities",), [float("nan")] * 8), False),
]


def _nest(depth: int, inner):
    for _ in range(depth):
        inner = [inner]
    return inner


# The top object is depth 0, its values depth 1: "note" at the top holding n nested lists
# puts the innermost list at depth n (the core allows 32 containers around a value).
STRUCTURE += [
    ("32 nested lists (allowed)", _set(("note",), _nest(31, [])), True),
    ("a value inside 32 nested lists", _set(("note",), _nest(32, 1)), False),
    ("33 nested lists", _set(("note",), _nest(32, [])), False),
    # The colour record is at depth 3, its "note" at 4: 28 lists put the {} at 32.
    ("a deep colour record", _set(C + ("note",), _nest(28, {})), True),
    ("a deeper colour record", _set(C + ("note",), _nest(29, {})), False),
]


@pytest.mark.parametrize("what, mutate, ok", STRUCTURE, ids=[c[0] for c in STRUCTURE])
def test_both_readers_give_one_verdict_on_structure(base, tmp_path, what, mutate, ok):
    root, m = base
    bad = copy.deepcopy(m)
    mutate(bad)
    shutil.copytree(root / "p", tmp_path / "p")
    for ascii_only in (False, True):  # raw UTF-8 and \u escapes
        try:
            data = json.dumps(bad, ensure_ascii=ascii_only, allow_nan=True).encode()
        except UnicodeEncodeError:  # a lone surrogate has no raw UTF-8 form
            assert not ascii_only
            continue
        assert_agree(data, ok, tmp_path / "p")


def _text_edit(old: bytes, new: bytes, count: int = 1):
    return lambda text: text.replace(old, new, count)


# (what, edit of the manifest's UTF-8 bytes, whether both accept it)
TEXT = [
    ("a byte-order mark", lambda t: b"\xef\xbb\xbf" + t, False),
    ("two byte-order marks", lambda t: b"\xef\xbb\xbf\xef\xbb\xbf" + t, False),
    ("a UTF-16 byte-order mark", lambda t: b"\xff\xfe" + t, False),
    ("a byte-order mark after whitespace", lambda t: b" \xef\xbb\xbf" + t, False),
    ("leading and trailing whitespace (allowed)", lambda t: b" \r\n\t" + t + b"\n\n ", True),
    ("NaN literal", _text_edit(b'"format"', b'"note": NaN, "format"'), False),
    ("Infinity literal", _text_edit(b'"format"', b'"note": Infinity, "format"'), False),
    ("-Infinity literal", _text_edit(b'"format"', b'"note": -Infinity, "format"'), False),
    ("nan in lower case", _text_edit(b'"format"', b'"note": nan, "format"'), False),
    ("1e400", _text_edit(b'"format"', b'"note": 1e400, "format"'), False),
    ("-1e400", _text_edit(b'"format"', b'"note": -1e400, "format"'), False),
    ("1e-400 (allowed)", _text_edit(b'"format"', b'"note": 1e-400, "format"'), True),
    ("a 400-digit integer", _text_edit(b'"format"', b'"note": ' + b"9" * 400 + b', "format"'),
     False),
    ("a 5000-digit integer", _text_edit(b'"format"', b'"note": ' + b"9" * 5000 + b', "format"'),
     False),
    ("-0 where any value goes (allowed)", _text_edit(b'"format"', b'"note": -0, "format"'), True),
    ("a lone high surrogate escape", _text_edit(b'"format"', b'"note": "\\ud800", "format"'),
     False),
    ("a lone low surrogate escape", _text_edit(b'"format"', b'"note": "\\udc00x", "format"'),
     False),
    ("reversed surrogates", _text_edit(b'"format"', b'"note": "\\udc00\\ud800", "format"'),
     False),
    ("an escaped surrogate pair (allowed)",
     _text_edit(b'"format"', b'"note": "\\ud83d\\ude00", "format"'), True),
    ("a surrogate encoded in UTF-8 (CESU)",
     _text_edit(b'"format"', b'"note": "\xed\xa0\x80", "format"'), False),
    ("an overlong encoding", _text_edit(b'"format"', b'"note": "\xc0\xaf", "format"'), False),
    ("a lone continuation byte", _text_edit(b'"format"', b'"note": "\x80", "format"'), False),
    ("a truncated sequence", _text_edit(b'"format"', b'"note": "\xe2\x82", "format"'), False),
    ("above U+10FFFF", _text_edit(b'"format"', b'"note": "\xf4\x90\x80\x80", "format"'), False),
    ("Latin-1 in a name", _text_edit(b'"name": "', b'"name": "\xe9'), False),
    ("a raw control character in a string", _text_edit(b'"name": "', b'"name": "\x01'), False),
    ("a raw tab in a string", _text_edit(b'"name": "', b'"name": "\t'), False),
    ("a duplicate key, the later valid (allowed)",
     _text_edit(b'"format"', b'"tile_count": 0, "format"'), True),
    ("a comment", _text_edit(b'"format"', b'/* c */ "format"'), False),
    ("a trailing comma", _text_edit(b'"format"', b'"note": 1,, "format"'), False),
    ("single quotes", _text_edit(b'"format"', b"'note': 1, \"format\""), False),
    ("trailing garbage", lambda t: t + b"x", False),
    ("a second document", lambda t: t + b"{}", False),
    ("a NUL after the document", lambda t: t + b"\0", False),
    ("empty", lambda t: b"", False),
    ("hex number", _text_edit(b'"format"', b'"note": 0x10, "format"'), False),
    ("a leading plus", _text_edit(b'"format"', b'"note": +1, "format"'), False),
    ("a leading zero", _text_edit(b'"format"', b'"note": 01, "format"'), False),
]


@pytest.mark.parametrize("what, edit, ok", TEXT, ids=[c[0] for c in TEXT])
def test_both_readers_give_one_verdict_on_text(base, tmp_path, what, edit, ok):
    root, m = base
    shutil.copytree(root / "p", tmp_path / "p")
    assert_agree(edit(json.dumps(m).encode()), ok, tmp_path / "p")


# ----------------------------------------------------------------------------- hypothesis

hostile = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(-2 ** 70, 2 ** 70),
              st.sampled_from([2 ** 63, 2 ** 64 - 1, 2 ** 64, 10 ** 309, -2 ** 63 - 1, 127, 128]),
              st.floats(), st.sampled_from([536.0, 1e308, 1e-320, -0.0]),
              st.text(max_size=8),
              st.sampled_from(["\ud800", "a\udfff", "\udc00\ud800", "\ud83d\ude00"]),
              st.sampled_from(["convert", "keep", "embedded ICC profile", "EXR chromaticities",
                               "assumed sRGB", "default CMYK profile", "sRGB", "source", "RGB",
                               "GRAY", "CMYK", "mntr", "scnr", "prtr", "spac", "perceptual",
                               "relative", "saturation", "absolute", "a" * 64, "a" * 64 + "\n",
                               "f" * 63])),
    lambda kids: st.one_of(st.lists(kids, max_size=8), st.dictionaries(st.text(max_size=4), kids,
                                                                       max_size=3)),
    max_leaves=10)

COLOUR_KEYS = ["mode", "source_space", "profile", "stored_space", "transform", "chromaticities",
               "intent", "black_point_compensation", "note"]
PROFILE_KEYS = ["description", "sha256", "bytes", "colour_space", "class", "note"]


@st.composite
def colour_mutations(draw, m):
    """1 to 4 edits of the first painting's colour record or its profile: a key set to a
    hostile value or dropped."""
    m = copy.deepcopy(m)
    for _ in range(draw(st.integers(1, 4))):
        colour = m["paintings"][0]["colour"]
        target, keys = colour, COLOUR_KEYS
        if isinstance(colour.get("profile"), dict) and draw(st.booleans()):
            target, keys = colour["profile"], PROFILE_KEYS
        key = draw(st.sampled_from(keys))
        if draw(st.integers(0, 4)) == 0:
            target.pop(key, None)
        else:
            target[key] = draw(hostile)
    return m


def test_fuzz_colour_records_and_hostile_values_agree(base):
    _, m = base

    @settings(max_examples=400, deadline=None, database=None,
              suppress_health_check=list(HealthCheck))
    @given(colour_mutations(m), st.booleans())
    def run(mutated, ascii_only):
        try:
            data = json.dumps(mutated, ensure_ascii=ascii_only, allow_nan=True).encode()
        except UnicodeEncodeError:  # a lone surrogate has no raw UTF-8 form
            return
        out = verdicts(data)
        assert len({v == "ok" for v in out.values()}) == 1, {k: v[:200] for k, v in out.items()}

    run()


# ----------------------------------------------------------------------------- resumed shards

@pytest.fixture(scope="module")
def failed_build(tmp_path_factory):
    """A sharded build (process pool) that failed on painting 1, a truncated PNG whose
    header reads: shard 0 is complete in OUT.shards/. Returns (inputs, out, full bytes of
    painting 1's file)."""
    from PIL import Image
    root = tmp_path_factory.mktemp("resume-colour")
    rng = np.random.default_rng(9)
    good, bad = root / "a.png", root / "b.png"
    Image.fromarray(rng.integers(0, 256, (40, 50, 3), np.uint8)).save(good)
    Image.fromarray(rng.integers(0, 256, (300, 300, 3), np.uint8)).save(bad)
    full = bad.read_bytes()
    bad.write_bytes(full[:len(full) // 3])
    out = root / "o.pack"
    with pytest.raises(OSError, match="corrupt or truncated"):
        build_pack([good, bad], out, tile_size=16, border=2, workers=1, executor="processes")
    return [good, bad], out, full


def _edited(record: dict, edit) -> dict:
    r = copy.deepcopy(record)
    edit(r)
    return r


# (what, edit of shard 0's record, whether resume may reuse the shard)
RECORD_EDITS = [
    ("unedited", lambda r: None, True),
    ("colour mode off the schema", lambda r: r["colour"].update(mode="maybe"), False),
    ("colour record dropped to a list", lambda r: r.update(colour=[1]), False),
    ("colour NaN", lambda r: r["colour"].update(transform=float("nan")), False),
    ("colour valid but edited", lambda r: r["colour"].update(stored_space="source"), False),
    ("name edited", lambda r: r.update(name="other"), False),
    ("width as a string", lambda r: r.update(width=str(r["width"])), False),
    ("source not a string", lambda r: r.update(source=None), False),
    ("no digest (an older record)", lambda r: r.pop("record_xxh3"), False),
    ("a lone surrogate in the name", lambda r: r.update(name="a\ud800"), False),
]


@pytest.mark.parametrize("what, edit, reusable", RECORD_EDITS, ids=[c[0] for c in RECORD_EDITS])
def test_resume_reuses_only_unedited_valid_records(failed_build, tmp_path, what, edit, reusable):
    from gigascroll.pack.shards import _completed_shard
    _, out, _ = failed_build
    shards = tmp_path / "s"
    shutil.copytree(out.parent / "o.pack.shards", shards)
    record = json.loads((shards / "shard-00000.json").read_text())
    assert record["colour"]["mode"] == "convert"
    (shards / "shard-00000.json").write_text(json.dumps(_edited(record, edit), allow_nan=True))
    reused = _completed_shard(shards, 0, record["job"])
    assert (reused is not None) == reusable


def test_a_huge_record_is_not_read_in_full(failed_build, tmp_path):
    from gigascroll.pack.shards import _completed_shard
    _, out, _ = failed_build
    shards = tmp_path / "s"
    shutil.copytree(out.parent / "o.pack.shards", shards)
    record = json.loads((shards / "shard-00000.json").read_text())
    record["note"] = "x" * (4 << 20)
    (shards / "shard-00000.json").write_text(json.dumps(record))
    assert _completed_shard(shards, 0, record["job"]) is None


def test_the_merge_checks_every_record():
    from gigascroll.pack.shard_records import record_digest, record_problem
    record = {"name": "a", "width": 5, "height": 7, "source": "a.png", "conversion": "none",
              "colour": {"mode": "convert", "source_space": "assumed sRGB", "profile": None,
                         "stored_space": "sRGB", "transform": "none"},
              "tiles_xxh3": "0123456789abcdef", "index_xxh3": "0123456789abcdef"}
    record["record_xxh3"] = record_digest(record)
    assert record_problem(record) is None
    bad = _edited(record, lambda r: r["colour"].update(mode="maybe"))
    bad["record_xxh3"] = record_digest(bad)  # even with a matching digest
    assert "colour" in record_problem(bad)
    assert "tiles_xxh3" in record_problem(_edited(record, lambda r: r.update(tiles_xxh3="x")))


def test_a_resumed_build_never_copies_an_edited_colour_record(failed_build):
    """The issue's case: shard 0's colour record edited off the schema, then --resume. The
    shard is rebuilt (its tile file is a new one), the pack opens in both readers and its
    colour records are a single-process build's."""
    inputs, out, full = failed_build
    shards = out.parent / "o.pack.shards"
    rec = shards / "shard-00000.json"
    record = json.loads(rec.read_text())
    record["colour"]["mode"] = "maybe"
    rec.write_text(json.dumps(record))
    # Held open, the old tile file keeps its inode number: a new file cannot reuse it.
    with open(shards / "tiles-00000.bin", "rb") as old:
        inputs[1].write_bytes(full)  # painting 1 readable now
        pack = build_pack(inputs, out, tile_size=16, border=2, workers=1, executor="processes",
                          resume=True)
        assert os.stat(out / "tiles-00000.bin").st_ino != os.fstat(old.fileno()).st_ino  # rebuilt
    single = build_pack(inputs, out.parent / "single.pack", tile_size=16, border=2)
    assert [p.colour for p in pack.paintings] == [p.colour for p in single.paintings]
    with PurePack(out) as pure:
        assert [p.colour for p in pure.paintings] == [p.colour for p in single.paintings]
    assert (out / "manifest.json").read_bytes() == \
        (out.parent / "single.pack" / "manifest.json").read_bytes()
