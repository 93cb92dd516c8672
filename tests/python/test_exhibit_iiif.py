"""`exhibit build` writes the show's IIIF: a Presentation 3.0 manifest of the exhibition's
paintings, each canvas's image service an Image API export under --base-url. The show is
served by the standard library's HTTP server at that base, and every URL the manifest and the
info.json files name must resolve (checked with the Presentation rules of iiif_rules.py)."""

from __future__ import annotations

import functools
import http.server
import json
import threading
import urllib.request

import pytest
from iiif_rules import check_image_info, check_manifest, tile_urls
from test_exhibit import SHOW, write_images

from gigascroll.cli import main


@pytest.fixture(scope="module")
def served_show(tmp_path_factory):
    """A show built with --base-url pointing at a loopback server of its directory."""
    d = tmp_path_factory.mktemp("exhibit-iiif")
    write_images(d)
    (d / "show.toml").write_text(SHOW)
    show = d / "show"
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(show))
    handler.log_message = lambda *a: None
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    base = f"http://127.0.0.1:{httpd.server_address[1]}/iiif"
    assert main(["exhibit", "build", str(d / "show.toml"), "-o", str(show), "--no-bake",
                 "--base-url", base]) == 0
    threading.Thread(target=httpd.serve_forever, daemon=True).start()
    yield show, base
    httpd.shutdown()
    httpd.server_close()


def fetch(url: str) -> bytes:
    with urllib.request.urlopen(url, timeout=30) as r:
        assert r.status == 200
        return r.read()


def test_the_manifest_names_each_painting_and_resolves(served_show):
    show, base = served_show
    manifest = json.loads(fetch(f"{base}/manifest.json"))
    check_manifest(manifest)
    assert manifest["id"] == f"{base}/manifest.json"
    assert "Two studies" in json.dumps(manifest["label"])
    canvases = manifest["items"]
    titles = ["Red study", "Blue study"]
    assert len(canvases) == len(titles)   # the labels' own paintings are not canvases
    for canvas, title in zip(canvases, titles):
        assert title in json.dumps(canvas["label"])
        body = canvas["items"][0]["items"][0]["body"]
        service = body["service"][0]["id"]
        assert service.startswith(base + "/")
        info = json.loads(fetch(f"{service}/info.json"))
        check_image_info(info)
        assert info["id"] == service
        urls = tile_urls(info)
        assert urls
        for url in urls[:: max(1, len(urls) // 8)]:
            assert fetch(url)[:3] == b"\xff\xd8\xff"  # a JPEG, served
    red = canvases[0]
    assert red["rights"] == "https://creativecommons.org/publicdomain/zero/1.0/"
    assert "A. Painter" in json.dumps(red["metadata"])


def test_build_record_names_the_manifest(served_show):
    show, _ = served_show
    record = json.loads((show / "build.json").read_text())
    assert record["iiif"] == "iiif/manifest.json"
    assert (show / record["iiif"]).is_file()


def test_no_iiif_and_a_bad_base_url(tmp_path, capsys):
    write_images(tmp_path)
    (tmp_path / "show.toml").write_text(SHOW)
    assert main(["exhibit", "build", str(tmp_path / "show.toml"), "-o", str(tmp_path / "a"),
                 "--no-bake", "--no-iiif"]) == 0
    assert not (tmp_path / "a" / "iiif").exists()
    capsys.readouterr()
    assert main(["exhibit", "build", str(tmp_path / "show.toml"), "-o", str(tmp_path / "b"),
                 "--no-bake", "--base-url", "ftp://example/x"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "IIIF" in err[0]
    assert not (tmp_path / "b").exists()


COPIES = SHOW + """
[[paintings]]
title = "Red study, second copy"
image = "red.png"
width_cm = 80
height_cm = 60
hang = { wall = 2, along_m = 2.0 }
"""


def _pack_files(pack_dir):
    return {p.name: p.read_bytes() for p in sorted(pack_dir.iterdir()) if p.is_file()}


def test_copies_are_instances_and_workers_build_the_same_pack(tmp_path):
    """Two paintings of one image file: the second is an instance (stored once, the same
    samples); `--workers 1` (Dask) builds the pack byte for byte as the in-process build."""
    from gigascroll import TilePack

    write_images(tmp_path)
    (tmp_path / "show.toml").write_text(COPIES)
    assert main(["exhibit", "build", str(tmp_path / "show.toml"), "-o", str(tmp_path / "a"),
                 "--no-bake", "--no-iiif"]) == 0
    pack = TilePack(tmp_path / "a" / "paintings.pack")
    byname = {p.name: p for p in pack.paintings}
    original, copy = byname["red-study"], byname["red-study-second-copy"]
    manifest = json.loads((tmp_path / "a" / "paintings.pack" / "manifest.json").read_text())
    entries = {e["name"]: e for e in manifest["paintings"]}
    assert entries["red-study-second-copy"].get("instance_of") in ("red-study", 0)
    assert "instance_of" not in entries["red-study"]
    assert (copy.width, copy.height) == (original.width, original.height)
    for level in range(original.levels):
        nx, ny = original.level_tiles[level]
        for ty in range(ny):
            for tx in range(nx):
                assert (pack.read_tile(copy, level, tx, ty)
                        == pack.read_tile(original, level, tx, ty)).all()
    assert main(["exhibit", "build", str(tmp_path / "show.toml"), "-o", str(tmp_path / "b"),
                 "--no-bake", "--no-iiif", "--workers", "1"]) == 0
    assert _pack_files(tmp_path / "b" / "paintings.pack") == _pack_files(tmp_path / "a" / "paintings.pack")
