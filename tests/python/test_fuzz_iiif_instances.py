"""Fuzz families for issue 41 §3-4's entry points, each case in a forked child (fuzz_support):
`export --base-url` with hostile URLs, `build_pack(instances=...)` with hostile instance
lists, the Presentation manifest writer with hostile paintings, and `bench exhibition-full`'s
options. CLI cases end in exit 0 or one error line with exit 2; Python cases in ValueError,
TypeError or OSError, never a crash, a hang or a traceback."""

import numpy as np
import pytest
from fuzz_support import cli_message_ok, count_case, fork_worker, fuzz_settings  # noqa: F401
from hypothesis import given
from hypothesis import strategies as st

from gigascroll import build_pack

URLS = st.one_of(
    st.sampled_from(["http://h/x", "https://h:8443/a/b/", "http://[::1]:80/x", "http://h:0/x",
                     "http://h:65536/x", "http://h/x?q", "http://h/x#f", "file:///x", "x",
                     "http://", "http://h/\x00", "http://h/é", "http://h/" + "a" * 5000,
                     "HTTP://H/X", "http://h/a b", " http://h/x", "http://h/x\n", ""]),
    st.text(max_size=40))


@pytest.fixture(scope="module")
def small_pack(tmp_path_factory):
    rng = np.random.default_rng(5)
    path = tmp_path_factory.mktemp("fuzz-iiif") / "s.pack"
    build_pack([rng.integers(0, 256, (30, 50, 3), np.uint8)], path, tile_size=16, border=2,
               names=["s"])
    return str(path)


@fuzz_settings(15)
@given(url=URLS, fmt=st.sampled_from(["iiif", "iiif", "dzi"]))
def test_fuzz_export_base_url(fork_worker, small_pack, tmp_path_factory, url, fmt):
    count_case("export-base-url")
    out = tmp_path_factory.mktemp("o") / "x"
    o = fork_worker.run({"kind": "cli", "argv": ["export", small_pack, "-o", str(out),
                                                 "--format", fmt, "--base-url", url]})
    assert cli_message_ok(o) is None, f"--base-url {url!r}: {cli_message_ok(o)}\n{o.describe()}"


INSTANCE_ITEMS = st.one_of(
    st.tuples(st.text(max_size=6), st.one_of(st.integers(-3, 4), st.sampled_from(
        ["a", "b", "zz", ""]), st.none(), st.floats(allow_nan=True), st.booleans())),
    st.sampled_from([("x",), ("x", 0, 1), "x0", None, 3, ["y", 1]]))

_BUILD = """
from math import inf, nan
import numpy as np, gigascroll
from gigascroll.pack.reader import PurePack
imgs = [np.full((20, 30, 3), 7, np.uint8), np.full((9, 40, 3), 9, np.uint8)]
try:
    pk = gigascroll.build_pack(imgs, {out!r}, tile_size=16, border=2, names=["a", "b"],
                               instances={instances!r})
except (ValueError, TypeError, OSError):
    pass
else:
    pure = PurePack({out!r})
    for p, pp in enumerate(pk.paintings):
        src = p if pp.instance_of is None else pp.instance_of
        assert np.array_equal(pk.read_tile(p, 0, 0, 0), pk.read_tile(src, 0, 0, 0))
        assert np.array_equal(pure.read_tile(p, 0, 0, 0), pk.read_tile(p, 0, 0, 0))
"""


@fuzz_settings(15)
@given(instances=st.one_of(st.lists(INSTANCE_ITEMS, max_size=4), st.sampled_from(
    ["ab", {"x": 0}, 5, None, []])))
def test_fuzz_build_instances(fork_worker, tmp_path_factory, instances):
    count_case("build-instances")
    out = str(tmp_path_factory.mktemp("b") / "p.pack")
    o = fork_worker.run({"kind": "python", "code": _BUILD.format(out=out, instances=instances),
                         "memory": 2 << 30}, timeout=60)
    assert o.code == 0 and not o.timeout, f"instances={instances!r}\n{o.describe()}"


_MANIFEST = """
from math import inf, nan
from gigascroll.iiif_presentation import PresentationPainting, presentation_manifest
try:
    p = PresentationPainting(title={title!r}, width={width!r}, height={height!r},
                             service={service!r}, rights={rights!r}, size_cm={size!r})
    presentation_manifest([p], {mid!r}, {label!r})
except (ValueError, TypeError):
    pass
"""


@fuzz_settings(20)
@given(title=st.one_of(st.text(max_size=8), st.none(), st.integers()),
       width=st.one_of(st.integers(-2, 10**12), st.floats(), st.none(), st.booleans()),
       height=st.integers(-2, 10),
       service=URLS, mid=URLS, label=st.one_of(st.text(max_size=5), st.none()),
       rights=st.one_of(st.none(), st.sampled_from(
           ["http://creativecommons.org/licenses/by/4.0/", "x", ""]), st.integers()),
       size=st.one_of(st.none(), st.tuples(st.floats(), st.floats()),
                      st.sampled_from([(), "ab", (1,)])))
def test_fuzz_presentation_manifest(fork_worker, title, width, height, service, mid, label,
                                    rights, size):
    count_case("presentation-manifest")
    code = _MANIFEST.format(title=title, width=width, height=height, service=service,
                            rights=rights, size=size, mid=mid, label=label)
    o = fork_worker.run({"kind": "python", "code": code, "memory": 1 << 30}, timeout=30)
    assert o.code == 0 and not o.timeout, o.describe()


@fuzz_settings(10)
@given(argv=st.lists(st.sampled_from(["--scale", "1/0", "0", "-1/2", "1/65536", "1e9", "--parts",
                                      ",", "--seconds", "inf", "-1", "1e400",
                                      "--workers", "-5", "99999", "--eye", "0x0", "--methods",
                                      "nope"]), min_size=1, max_size=4))
def test_fuzz_bench_exhibition_full_options(fork_worker, tmp_path_factory, argv):
    count_case("bench-exhibition-full")
    d = tmp_path_factory.mktemp("e")
    # last, so they win: no part that builds (a full-size build is hours), no pack there
    argv = ["bench", "exhibition-full", *argv, "--work", str(d / "w"), "--out",
            str(d / "r.json"), "--parts", "multi"]
    o = fork_worker.run({"kind": "cli", "argv": argv, "memory": 2 << 30}, timeout=120)
    assert cli_message_ok(o) is None, f"{argv}: {cli_message_ok(o)}\n{o.describe()}"


@pytest.fixture(scope="module")
def two_pngs(tmp_path_factory):
    from PIL import Image
    d = tmp_path_factory.mktemp("pngs")
    Image.fromarray(np.full((20, 30, 3), 5, np.uint8)).save(d / "a.png")
    Image.fromarray(np.full((9, 12, 3), 9, np.uint8)).save(d / "b.png")
    return d


@fuzz_settings(12)
@given(items=st.lists(st.one_of(st.text(max_size=8), st.sampled_from(
    ["c=a", "c=1", "c=2", "c=-1", "a=0", "=", "c==a", "c=0x1", "c=١", "c=" + "9" * 30])),
    min_size=1, max_size=3))
def test_fuzz_pack_instance_option(fork_worker, two_pngs, tmp_path_factory, items):
    count_case("pack-instance")
    out = tmp_path_factory.mktemp("pi") / "p.pack"
    argv = ["pack", str(two_pngs / "a.png"), str(two_pngs / "b.png"), "-o", str(out),
            "--tile-size", "16", "--border", "2"]
    for item in items:
        argv.append(f"--instance={item}")
    o = fork_worker.run({"kind": "cli", "argv": argv, "memory": 2 << 30}, timeout=60)
    assert cli_message_ok(o) is None, f"{items!r}: {cli_message_ok(o)}\n{o.describe()}"


_SHOW = """
from math import inf, nan
from types import SimpleNamespace
from gigascroll.iiif_exhibition import write_exhibition_iiif
p = SimpleNamespace(title={title!r}, width_cm={w!r}, height_cm=10.0, name={name!r},
                    rights={rights!r})
try:
    write_exhibition_iiif({pack!r}, [p], {out!r}, {url!r}, label={label!r})
except (ValueError, TypeError, OSError):
    pass
"""


@fuzz_settings(12)
@given(title=st.one_of(st.text(max_size=6), st.none()), w=st.one_of(st.floats(), st.none()),
       name=st.sampled_from(["s", "x", "", None, "s/../s"]), url=URLS,
       rights=st.sampled_from([None, "x", "http://rightsstatements.org/vocab/InC/1.0/"]),
       label=st.one_of(st.text(max_size=5), st.none(), st.integers()))
def test_fuzz_exhibition_iiif(fork_worker, small_pack, tmp_path_factory, title, w, name, url,
                              rights, label):
    count_case("exhibition-iiif")
    out = str(tmp_path_factory.mktemp("x") / "show")
    code = _SHOW.format(title=title, w=w, name=name, rights=rights, pack=small_pack, out=out,
                        url=url, label=label)
    o = fork_worker.run({"kind": "python", "code": code, "memory": 2 << 30}, timeout=60)
    assert o.code == 0 and not o.timeout, o.describe()
