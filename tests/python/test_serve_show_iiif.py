"""`gigascroll serve --exhibition SHOW` serves the show's IIIF folder under /iiif/, so the
Presentation manifest's and the Image API's ids resolve at serve's own address when the show
was built with a --base-url there (exhibit build's default, http://localhost:8000/iiif, is
serve's default address). Every URL the manifest and the info.json files name is fetched and
checked with the Presentation 3.0 rules (iiif_rules.py); CORS is open as IIIF viewers need;
nothing outside the folder is served."""

from __future__ import annotations

import json
import socket
import urllib.error
import urllib.request

import pytest
from iiif_rules import check_image_info, check_manifest, tile_urls
from test_exhibit import SHOW, write_images

from gigascroll.cli import main


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    from gigascroll.exhibit.show import open_show
    from gigascroll.serve import ServerThread, make_app
    d = tmp_path_factory.mktemp("serve-iiif")
    write_images(d)
    (d / "show.toml").write_text(SHOW)
    port = _free_port()
    base = f"http://127.0.0.1:{port}/iiif"
    assert main(["exhibit", "build", str(d / "show.toml"), "-o", str(d / "show"), "--no-bake",
                 "--base-url", base]) == 0
    show = open_show(d / "show")
    with ServerThread(make_app(show.pack, None, iiif_dir=d / "show" / "iiif"),
                      port=port) as url:
        yield base, url.rstrip("/")


def fetch(url: str):
    try:
        with urllib.request.urlopen(url, timeout=30) as r:
            return r.status, dict(r.headers), r.read()
    except urllib.error.HTTPError as e:
        return e.code, dict(e.headers), e.read()


def test_every_id_resolves_at_serves_address(served):
    base, _ = served
    status, headers, body = fetch(f"{base}/manifest.json")
    assert status == 200 and headers["Access-Control-Allow-Origin"] == "*"
    manifest = json.loads(body)
    check_manifest(manifest)
    assert manifest["id"] == f"{base}/manifest.json"
    for canvas in manifest["items"]:
        image = canvas["items"][0]["items"][0]["body"]
        status, headers, _ = fetch(image["id"])
        assert status == 200 and headers["Content-Type"] == "image/jpeg"
        status, _, info = fetch(image["service"][0]["id"] + "/info.json")
        info = json.loads(info)
        check_image_info(info)
        urls = tile_urls(info)
        for u in urls[:3] + urls[-3:]:
            assert fetch(u)[0] == 200, u


@pytest.mark.parametrize("path", ["../exhibition.json", "%2e%2e/exhibition.json",
                                  "red-study/../../build.json", ".mark", "red-study",
                                  "manifest.json/x", "x.py", ""])
def test_nothing_else_is_served(served, path):
    _, url = served
    assert fetch(f"{url}/iiif/{path}")[0] == 404

