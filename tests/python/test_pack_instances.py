"""Pack instances: a painting that is an instance of another (its own name and page-table
placement, the source's tile data). Checked against a pack holding real copies of the same
images in the same order (the same layout, so the same placements): every tile and every
sample equal, the feedback / request processing of an exhibition view identical frame by
frame; the tile data stored once (the pack is the distinct paintings' pack plus a longer
manifest); both readers agree on instance manifests and refuse bad ones; a pack without
instances is byte for byte what the format wrote before instances existed."""

import copy
import hashlib
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from gigascroll import TilePack, VirtualTexture, _core, build_pack
from gigascroll import views as v
from gigascroll.walk.frame_loop import FrameLoop
from gigascroll.pack.reader import PurePack, parse_manifest_text

SIZES = [(150, 90), (70, 120), (96, 40)]          # (width, height): three distinct scans
INSTANCES = [("a2", 0), ("b2", "b"), ("c2", 2), ("a3", "a"), ("b3", 1), ("c3", "c")]
ORDER = [0, 1, 2, 0, 1, 2, 0, 1, 2]               # the source of each painting of the pack


def images():
    rng = np.random.default_rng(41)
    return [rng.integers(0, 256, (h, w, 3), np.uint8) for w, h in SIZES]


@pytest.fixture(scope="module")
def packs(tmp_path_factory):
    root = tmp_path_factory.mktemp("instances")
    imgs = images()
    kw = dict(tile_size=32, border=2, codec="zstd")
    inst = build_pack(imgs, root / "inst.pack", names=["a", "b", "c"], instances=INSTANCES, **kw)
    copies = build_pack([imgs[i] for i in ORDER], root / "copies.pack",
                        names=["a", "b", "c"] + [n for n, _ in INSTANCES], **kw)
    distinct = build_pack(imgs, root / "distinct.pack", names=["a", "b", "c"], **kw)
    return root, inst, copies, distinct


def files(pack_dir):
    return {p.name: p.read_bytes() for p in sorted(pack_dir.iterdir())}


def test_the_manifest_names_the_sources(packs):
    _, inst, copies, _ = packs
    assert [p.name for p in inst.paintings] == [p.name for p in copies.paintings]
    assert [p.instance_of for p in inst.paintings] == [None] * 3 + ORDER[3:]
    assert [p.instance_of for p in copies.paintings] == [None] * 9
    # the same layout: every painting's page table where the copies' is
    assert [p.table_offset for p in inst.paintings] == [p.table_offset for p in copies.paintings]
    assert inst.table_size == copies.table_size
    assert len({p.table_offset for p in inst.paintings}) == 9
    pure = PurePack(inst.path)
    assert [p.instance_of for p in pure.paintings] == [p.instance_of for p in inst.paintings]


def test_tiles_are_stored_once(packs):
    _, inst, _, distinct = packs
    a, d = files(Path(inst.path)), files(Path(distinct.path))
    assert set(a) == set(d) == {"manifest.json", "index.bin", "tiles-00000.bin",
                                "tiles-00001.bin", "tiles-00002.bin"}
    for name in a:  # the tile data and the index are the distinct paintings' pack's
        if name != "manifest.json":
            assert a[name] == d[name], name
    assert inst.tile_count == distinct.tile_count


def test_every_tile_equals_the_copies(packs):
    _, inst, copies, _ = packs
    pure = PurePack(inst.path)
    n = 0
    for p, pp in enumerate(copies.paintings):
        for level, (nx, ny) in enumerate(pp.level_tiles):
            for ty in range(ny):
                for tx in range(nx):
                    want = copies.read_tile(p, level, tx, ty)
                    assert np.array_equal(inst.read_tile(p, level, tx, ty), want)
                    assert np.array_equal(pure.read_tile(p, level, tx, ty), want)
                    n += 1
    assert n == sum(p.tile_count for p in copies.paintings)


def test_every_sample_equals_the_copies(packs):
    _, inst, copies, _ = packs
    u, w = np.meshgrid(np.linspace(0, 1, 37), np.linspace(0, 1, 23))
    for lod in (0.0, 0.7, 1.5, None):
        caches = [VirtualTexture(pk, slots=(12, 12)) for pk in (inst, copies)]
        for vt, pk in zip(caches, (inst, copies)):
            keys = [(p, l, tx, ty) for p, pp in enumerate(pk.paintings)
                    for l, (nx, ny) in enumerate(pp.level_tiles) if l <= 1
                    for ty in range(ny) for tx in range(nx)][:100]
            for k in keys:
                if not vt.is_resident(k):
                    vt.insert(k, pk.read_tile(*k))
        for p in range(9):
            a, la = caches[0].sample(p, u, w, lod=lod, filter="trilinear")
            b, lb = caches[1].sample(p, u, w, lod=lod, filter="trilinear")
            assert np.array_equal(a, b) and np.array_equal(la, lb), (p, lod)


def test_an_exhibition_view_is_identical_frame_by_frame(packs):
    _, inst, copies, _ = packs
    specs = [v.PaintingSpec(f"s{i}", w, h, w / 300, h / 300) for i, (w, h) in enumerate(SIZES)]
    ex = v.multi_exhibition(9, specs, tile_size=32, border=2)
    path = v.multi_route(9, duration=6 / v.FPS, specs=specs)
    runs = []
    for pk in (inst, copies):
        loop = FrameLoop(ex, pk, path, method="hash", pace=False, wait_loads=True,
                         slots=(16, 16), per_frame=8, magnifier=False)
        loop.run()
        keep = [{k: r[k] for k in r if not k.endswith(("_ms", "_s"))} for r in loop.records]
        runs.append((keep, loop.last_images))
    (ra, ia), (rb, ib) = runs
    assert ra == rb
    assert sum(r["loaded"] for r in ra) > 0 and min(r["requests"] for r in ra) > 0
    assert all(np.array_equal(x, y) for x, y in zip(ia, ib)) and ia


# ----------------------------------------------------------------------------- old packs

def _digest(pack_dir) -> str:
    h = hashlib.sha256()
    for name, data in files(Path(pack_dir)).items():
        h.update(name.encode() + b"\0" + data)
    return h.hexdigest()


def test_a_pack_without_instances_is_the_format_before_them(tmp_path):
    """The bytes of a small pack without instances stay what they are: the digest was
    recorded when instances were added, after a pack of two TIFFs built by the previous
    builder was found byte for byte equal to one built by the new one."""
    imgs = images()
    a = build_pack(imgs, tmp_path / "a", tile_size=32, border=2, names=["a", "b", "c"])
    b = build_pack(imgs, tmp_path / "b", tile_size=32, border=2, names=["a", "b", "c"],
                   instances=[])
    assert files(tmp_path / "a") == files(tmp_path / "b")
    m = json.loads((tmp_path / "a" / "manifest.json").read_text())
    assert m["version"] == 2 and all("instance_of" not in p for p in m["paintings"])
    assert _digest(tmp_path / "a") == OLD_FORMAT_DIGEST


OLD_FORMAT_DIGEST = "b212fc71428e836b619ae978f730ddce9406a93589d084b9fe869f5356558ede"


# ----------------------------------------------------------------------------- one verdict

def verdicts(text: str, pack_dir) -> dict:
    out = {}
    for name, f in (("core text", lambda: _core.check_manifest(text)),
                    ("pure text", lambda: parse_manifest_text(text)),
                    ("core pack", lambda: TilePack(pack_dir)),
                    ("pure pack", lambda: PurePack(pack_dir).close())):
        if name.endswith("pack"):
            (pack_dir / "manifest.json").write_text(text)
        try:
            f()
            out[name] = "ok"
        except (ValueError, OSError) as e:
            out[name] = f"refuses: {e}"[:160]
    return out


def _mutate(path, value):
    def f(m):
        node = m
        for k in path[:-1]:
            node = node[k]
        if value is KeyError:
            del node[path[-1]]
        else:
            node[path[-1]] = value
    return f


P3 = ("paintings", 3)
MUTATIONS = [
    ("as built", lambda m: None, True),
    ("an instance of a later painting", _mutate(P3 + ("instance_of",), 5), False),
    ("an instance of itself", _mutate(P3 + ("instance_of",), 3), False),
    ("an instance of an instance", _mutate(("paintings", 6, "instance_of"), 3), False),
    ("an instance of another size", _mutate(P3 + ("instance_of",), 1), False),
    ("instance_of out of range", _mutate(P3 + ("instance_of",), 70000), False),
    ("instance_of negative", _mutate(P3 + ("instance_of",), -1), False),
    ("instance_of a float", _mutate(P3 + ("instance_of",), 0.0), False),
    ("instance_of true", _mutate(P3 + ("instance_of",), True), False),
    ("instance_of a string", _mutate(P3 + ("instance_of",), "0"), False),
    ("an instance's own entries", _mutate(P3 + ("first_entry",), 0), None),
    ("the instance tag dropped", _mutate(P3 + ("instance_of",), KeyError), False),
    ("a stored painting tagged", _mutate(("paintings", 1, "instance_of"), 0), False),
    ("version 1", lambda m: (m.update(version=1), m.pop("tile_files")), False),
]


@pytest.mark.parametrize("what, mutate, ok", MUTATIONS, ids=[c[0] for c in MUTATIONS])
def test_both_readers_give_one_verdict(packs, tmp_path, what, mutate, ok):
    root, inst, _, _ = packs
    m = json.loads((root / "inst.pack" / "manifest.json").read_text())
    if ok is None:  # the source's first entry, written out: still valid (it is the same)
        m["paintings"][3]["first_entry"] = m["paintings"][0]["first_entry"]
        ok = True
    mutate(m)
    shutil.copytree(root / "inst.pack", tmp_path / "p")
    out = verdicts(json.dumps(m, indent=2), tmp_path / "p")
    assert {val == "ok" for val in out.values()} == {ok}, out


# ----------------------------------------------------------------------------- builds

def test_sharded_build_gives_the_same_pack(packs, tmp_path):
    root, inst, _, _ = packs
    sharded = build_pack(images(), tmp_path / "s.pack", tile_size=32, border=2, codec="zstd",
                         names=["a", "b", "c"], instances=INSTANCES, workers=2,
                         executor="processes")
    assert files(Path(sharded.path)) == files(root / "inst.pack")


@pytest.mark.parametrize("instances, match", [
    ([("x", 3)], "not an input index"), ([("x", -1)], "not an input index"),
    ([("x", "zz")], "no input painting named"), ([("a", 0)], "already a painting's name"),
    ([("x", 0), ("x", 1)], "already a painting's name"), ([("x",)], "pair"),
    ("x", "pairs"), (5, "pairs, not int"), ([("", 0)], "non-empty"), ([("x", 1.0)], "index or name"),
    ([("x", True)], "index or name")])
def test_bad_instances(tmp_path, instances, match):
    with pytest.raises(ValueError, match=match):
        build_pack(images(), tmp_path / "bad.pack", tile_size=32, border=2,
                   names=["a", "b", "c"], instances=instances)
    assert not (tmp_path / "bad.pack").exists()


def test_builder_order_rules(tmp_path):
    b = _core.PackBuilder(tmp_path, 32, 2)
    with pytest.raises(ValueError, match="stored paintings"):
        b.add_instance("x", 0)
    img = images()[2]
    b.begin_painting("c", img.shape[1], img.shape[0])
    b.add_rows(img)
    b.end_painting()
    b.add_instance("x", 0, 32, 0)
    with pytest.raises(ValueError, match="instances come after"):
        b.begin_painting("d", 10, 10)


def test_info_and_verify(packs, gigascroll_cli):
    from gigascroll.pack.inspect import verify_pack
    _, inst, copies, _ = packs
    assert verify_pack(inst) == inst.tile_count < verify_pack(copies)
    r = gigascroll_cli("info", "--verify", inst.path)
    assert r.returncode == 0, r.stderr
    assert r.stdout.count("an instance of [0] a:") == 2
    assert f"verified {inst.tile_count} tiles" in r.stdout


def test_the_pack_command_takes_instances(gigascroll_cli, tmp_path):
    from PIL import Image
    for name, img in zip("ab", images()[:2]):
        Image.fromarray(img).save(tmp_path / f"{name}.png")
    r = gigascroll_cli("pack", "a.png", "b.png", "-o", "p.pack", "--tile-size", "32",
                       "--border", "2", "--instance", "a=b=0", "--instance", "b2=b",
                       cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    pack = TilePack(tmp_path / "p.pack")
    assert [(p.name, p.instance_of) for p in pack.paintings] == \
        [("a", None), ("b", None), ("a=b", 0), ("b2", 1)]
    for bad, match in (("x", "NAME=SOURCE"), ("=0", "NAME=SOURCE"), ("x=", "NAME=SOURCE"),
                       ("x=7", "not an input index"), ("x=c", "no input painting"),
                       ("a=0", "already a painting")):
        r = gigascroll_cli("pack", "a.png", "b.png", "-o", "q.pack", "--instance", bad,
                           cwd=tmp_path)
        assert r.returncode == 2 and match in r.stderr and "Traceback" not in r.stderr, r.stderr
        assert not (tmp_path / "q.pack").exists()
