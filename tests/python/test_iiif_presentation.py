"""IIIF: the Image API export's ids resolve (every tile URL a client derives from info.json is
a file of the export, and is served over HTTP at its base URL), and the exhibition's
Presentation 3.0 manifest follows the specification's rules (tests/python/iiif_rules.py,
written from the specification's text) and points at the export's image services."""

import copy
import functools
import http.server
import io
import json
import threading
import urllib.request
from pathlib import Path
from urllib.parse import urlsplit

import numpy as np
import pytest
from iiif_rules import check_image_info, check_manifest, tile_urls
from PIL import Image

from gigascroll import build_pack
from gigascroll.iiif_presentation import (PresentationPainting, check_rights,
                                          painting_from_info, presentation_manifest,
                                          write_presentation_manifest)


@pytest.fixture(scope="module")
def pack(tmp_path_factory):
    rng = np.random.default_rng(41)
    a = rng.integers(0, 256, (150, 230, 3), np.uint8)
    b = rng.integers(0, 256, (40, 90, 3), np.uint8)
    return build_pack([a, b], tmp_path_factory.mktemp("iiif") / "two.pack", tile_size=64,
                      border=4, names=["landscape", "scroll"])


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """A plain static HTTP server (the standard library's) on a free port, serving `root`."""
    root = tmp_path_factory.mktemp("www")
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(root))
    handler.log_message = lambda *a: None
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=httpd.serve_forever, daemon=True).start()
    yield root, f"http://127.0.0.1:{httpd.server_address[1]}"
    httpd.shutdown()


def export(cli, pack, out, *extra):
    r = cli("export", pack.path, "-o", out, "--format", "iiif", *extra)
    assert r.returncode == 0, r.stderr
    return json.loads((Path(out) / "info.json").read_text())


def test_default_base_url_maps_every_tile_to_a_file(gigascroll_cli, pack, tmp_path):
    info = export(gigascroll_cli, pack, tmp_path / "landscape")
    check_image_info(info)
    # The default: where `python -m http.server 8000` in the output's parent serves it.
    assert info["id"] == "http://localhost:8000/landscape"
    urls = tile_urls(info)
    assert len(urls) > 10
    for url in urls:
        path = tmp_path / urlsplit(url).path.lstrip("/")
        assert path.is_file(), url
    # and nothing else: every JPEG of the export is one of those URLs
    files = {p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("default.jpg")}
    assert files - {"landscape/full/max/0/default.jpg"} == \
        {urlsplit(u).path.lstrip("/") for u in urls}


def test_base_url_is_served(gigascroll_cli, pack, server):
    root, base = server
    info = export(gigascroll_cli, pack, root / "scroll", "--painting", "scroll", "--base-url",
                  f"{base}/scroll/")
    assert info["id"] == f"{base}/scroll"  # no trailing slash: clients append "/info.json"
    with urllib.request.urlopen(f"{info['id']}/info.json") as r:
        assert json.loads(r.read()) == info
    for url in tile_urls(info):
        size = tuple(int(v) for v in url.split("/")[-3].split(","))
        with urllib.request.urlopen(url) as r:
            assert Image.open(io.BytesIO(r.read())).size == size, url


@pytest.mark.parametrize("bad", ["scroll", "ftp://host/x", "http:///x", "http://h/x?y=1",
                                 "http://h/x#f", "http://h:99999/x", "//h/x", "http://h/a b"])
def test_base_url_errors(gigascroll_cli, pack, tmp_path, bad):
    r = gigascroll_cli("export", pack.path, "-o", tmp_path / "x", "--format", "iiif",
                       "--base-url", bad)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert "--base-url" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "x").exists()


def test_base_url_only_for_iiif(gigascroll_cli, pack, tmp_path):
    r = gigascroll_cli("export", pack.path, "-o", tmp_path / "x.tif", "--format", "tiff",
                       "--base-url", "http://h/x")
    assert r.returncode == 2 and "iiif only" in r.stderr


def test_manifest_follows_presentation_3(gigascroll_cli, pack, server):
    root, base = server
    show = root / "show"
    show.mkdir()
    meta = {"landscape": dict(artist="Anon.", date="c. 1100", credit="Gift of a friend",
                              rights="http://creativecommons.org/publicdomain/mark/1.0/",
                              size_cm=(230.0, 150.0), accession="1941.41"),
            "scroll": dict(artist="Someone", rights="http://rightsstatements.org/vocab/InC/1.0/")}
    paintings = []
    for name, m in meta.items():
        export(gigascroll_cli, pack, show / name, "--painting", name, "--base-url",
               f"{base}/show/{name}")
        paintings.append(painting_from_info(show / name / "info.json", name.title(), **m))
    path = write_presentation_manifest(show / "manifest.json", paintings,
                                       f"{base}/show/manifest.json", "A small show")
    with urllib.request.urlopen(f"{base}/show/manifest.json") as r:
        m = json.loads(r.read())
    check_manifest(m)
    assert m == json.loads(path.read_text())
    assert [c["label"] for c in m["items"]] == [{"en": ["Landscape"]}, {"en": ["Scroll"]}]
    for canvas, name in zip(m["items"], meta):
        info = json.loads((show / name / "info.json").read_text())
        assert (canvas["width"], canvas["height"]) == (info["width"], info["height"])
        (body,) = [a["body"] for page in canvas["items"] for a in page["items"]]
        assert body["service"][0]["id"] == info["id"]
        assert body["service"][0]["profile"] == info["profile"]
        with urllib.request.urlopen(body["id"]) as r:  # the body is an image of the export
            assert Image.open(io.BytesIO(r.read())).size == (body["width"], body["height"])
        assert canvas["rights"] == meta[name]["rights"]
    land = m["items"][0]
    assert land["requiredStatement"]["value"] == {"en": ["Gift of a friend"]}
    rows = {r["label"]["en"][0]: r["value"]["en"][0] for r in land["metadata"]}
    assert rows == {"Artist": "Anon.", "Date": "c. 1100", "Accession number": "1941.41",
                    "Dimensions": "150 x 230 cm (height x width)"}
    assert "requiredStatement" not in m["items"][1]


def good_manifest():
    p = PresentationPainting("T", 300, 200, "https://example.org/iiif/t", artist="A",
                             credit="C", rights="http://creativecommons.org/licenses/by/4.0/")
    return presentation_manifest([p, p], "https://example.org/show/manifest.json", "Show")


def _set(path, value):
    def mutate(m):
        node = m
        for k in path[:-1]:
            node = node[k]
        if value is KeyError:
            del node[path[-1]]
        else:
            node[path[-1]] = value
    return mutate


ANNO = ["items", 0, "items", 0, "items", 0]
MUTATIONS = {
    "no label": _set(["label"], KeyError),
    "label a string": _set(["label"], "Show"),
    "relative id": _set(["id"], "manifest.json"),
    "wrong type": _set(["type"], "Collection"),
    "float width": _set(["items", 0, "width"], 300.0),
    "no height": _set(["items", 0, "height"], KeyError),
    "motivation": _set(ANNO + ["motivation"], "commenting"),
    "target": _set(ANNO + ["target"], "https://example.org/show/canvas/2"),
    "service type": _set(ANNO + ["body", "service", 0, "type"], "ImageService2"),
    "rights": _set(["items", 0, "rights"], "https://example.org/my-licence"),
    "metadata value": _set(["items", 0, "metadata", 0, "value"], ["A"]),
    "repeated ids": _set(["items", 1, "id"], "https://example.org/show/canvas/1"),
    "context": _set(["@context"], "http://iiif.io/api/presentation/2/context.json"),
}


def test_the_rules_accept_ours_and_catch_each_mutation():
    check_manifest(good_manifest())
    for name, mutate in MUTATIONS.items():
        m = copy.deepcopy(good_manifest())
        mutate(m)
        with pytest.raises(AssertionError):
            check_manifest(m)
            pytest.fail(f"the rules missed: {name}")


@pytest.mark.parametrize("uri", ["http://creativecommons.org/licenses/by-nc-sa/4.0/",
                                 "https://creativecommons.org/publicdomain/zero/1.0/",
                                 "http://rightsstatements.org/vocab/NoC-US/1.0/"])
def test_rights_accepted(uri):
    assert check_rights(uri) == uri


@pytest.mark.parametrize("uri", ["CC-BY", "http://creativecommons.org/licenses/by/4.0",
                                 "http://creativecommons.org/licenses/by-xx/4.0/",
                                 "https://rightsstatements.org/page/InC/1.0/",
                                 "https://example.org/licence", "", None, 3])
def test_rights_refused(uri):
    with pytest.raises(ValueError, match="Creative Commons or RightsStatements"):
        check_rights(uri)


@pytest.mark.parametrize("change, match", [
    (dict(service="t"), "absolute"), (dict(width=0), "positive integer"),
    (dict(height=2.5), "positive integer"), (dict(title=" "), "title"),
    (dict(rights="public domain"), "Creative Commons"), (dict(image="ftp://x/y.jpg"), "absolute")])
def test_presentation_errors(change, match):
    base = dict(title="T", width=10, height=10, service="http://h/t")
    with pytest.raises(ValueError, match=match):
        presentation_manifest([PresentationPainting(**{**base, **change})], "http://h/m.json", "S")
    with pytest.raises(ValueError, match="at least one"):
        presentation_manifest([], "http://h/m.json", "S")
    with pytest.raises(TypeError):
        presentation_manifest([base], "http://h/m.json", "S")


def test_the_python_api_has_the_same_default(pack, tmp_path):
    from gigascroll.export import export_pack
    out = export_pack(pack.path, tmp_path / "my painting", "iiif", painting="scroll")
    info = json.loads((out / "info.json").read_text())
    assert info["id"] == "http://localhost:8000/my%20painting"
    check_image_info(info)
    with pytest.raises(ValueError, match="absolute"):
        export_pack(pack.path, tmp_path / "x", "iiif", service_id="x")
    with pytest.raises(ValueError, match="iiif format only"):
        export_pack(pack.path, tmp_path / "x.tif", "tiff", service_id="http://h/x")
    assert not (tmp_path / "x").exists() and not (tmp_path / "x.tif").exists()


def test_an_exhibition_painting_becomes_a_canvas(gigascroll_cli, pack, tmp_path):
    from gigascroll.exhibit.model import Painting
    from gigascroll.iiif_presentation import exhibition_painting
    p = Painting(0, "Landscape", 230.0, 150.0, "landscape", artist="Anon.", date="1100",
                 credit="Lent", rights="http://rightsstatements.org/vocab/NoC-US/1.0/")
    info = export(gigascroll_cli, pack, tmp_path / "landscape")
    entry = exhibition_painting(p, "http://localhost:8000/landscape/", info=tmp_path /
                                "landscape" / "info.json")
    assert (entry.width, entry.height, entry.size_cm) == (230, 150, (230.0, 150.0))
    m = presentation_manifest([entry, exhibition_painting(p, "https://h/s", width=4, height=3)],
                              "https://h/show/manifest.json", "Show")
    check_manifest(m)
    assert m["items"][0]["rights"] == p.rights and m["items"][1]["width"] == 4
    assert info["id"] == entry.service
    with pytest.raises(ValueError, match="is not the service"):
        exhibition_painting(p, "http://other/x", info=tmp_path / "landscape" / "info.json")
    with pytest.raises(ValueError, match="pixel size"):
        exhibition_painting(p, "https://h/s")


def test_an_exhibition_as_iiif(pack, server):
    """write_exhibition_iiif: every painting's tiles and the manifest in one directory; served
    at its base URL, the manifest follows the rules and each URL it names and each tile URL
    its services' info.json derive resolves."""
    from gigascroll.exhibit.model import Painting
    from gigascroll.iiif_exhibition import write_exhibition_iiif
    root, base = server
    paintings = [Painting(0, "The landscape", 230.0, 150.0, "landscape", artist="Anon.",
                          rights="http://creativecommons.org/publicdomain/mark/1.0/"),
                 Painting(1, "A scroll", 90.0, 40.0, "scroll", credit="Lent by a friend")]
    out = root / "show iiif"
    path = write_exhibition_iiif(pack.path, paintings, out, f"{base}/show%20iiif",
                                 label="A show")
    assert path == out / "manifest.json"
    with urllib.request.urlopen(f"{base}/show%20iiif/manifest.json") as r:
        m = json.loads(r.read())
    check_manifest(m)
    assert [c["label"]["en"][0] for c in m["items"]] == ["The landscape", "A scroll"]
    n = 0
    for canvas in m["items"]:
        (body,) = [a["body"] for page in canvas["items"] for a in page["items"]]
        with urllib.request.urlopen(body["service"][0]["id"] + "/info.json") as r:
            info = json.loads(r.read())
        assert (info["width"], info["height"]) == (canvas["width"], canvas["height"])
        for url in tile_urls(info) + [body["id"]]:
            with urllib.request.urlopen(url) as r:
                assert r.status == 200 and r.read(2) == b"\xff\xd8", url  # a JPEG
            n += 1
    assert n > 20
    # written again only with force, over its own output; never over something else
    with pytest.raises(OSError):
        write_exhibition_iiif(pack.path, paintings, out, f"{base}/x", label="A show")
    write_exhibition_iiif(pack.path, paintings[:1], out, f"{base}/x", label="A show", force=True)
    assert len(json.loads((out / "manifest.json").read_text())["items"]) == 1
    (root / "other").mkdir()
    (root / "other" / "keep.txt").write_text("mine")
    with pytest.raises(OSError):
        write_exhibition_iiif(pack.path, paintings, root / "other", f"{base}/o", label="S",
                              force=True)
    assert (root / "other" / "keep.txt").read_text() == "mine"


@pytest.mark.parametrize("change, match", [
    (dict(name="nope"), "holds no painting"), (dict(rights="CC-BY"), "Creative Commons")])
def test_an_exhibition_as_iiif_errors(pack, tmp_path, change, match):
    from gigascroll.exhibit.model import Painting
    from gigascroll.iiif_exhibition import write_exhibition_iiif
    p = Painting(0, "T", 1.0, 1.0, **{"name": "landscape", **change})
    with pytest.raises(ValueError, match=match):
        write_exhibition_iiif(pack.path, [p], tmp_path / "o", "http://h/o", label="S")
    assert list(tmp_path.iterdir()) == []  # no output, no temporary left
