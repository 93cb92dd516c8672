"""The IIIF rules the tests check outputs against, written from the specifications' text
(Presentation API 3.0 and Image API 3.0, iiif.io), independently of the writers: no code
of gigascroll's is used here. (The official Presentation 3.0 JSON Schema is not packaged on
PyPI, and iiif-prezi3, whose pydantic models would do, pins Pillow <= 12.0.0 below ours.)"""

from __future__ import annotations

import math
import re
from urllib.parse import urlsplit

PRESENTATION_CONTEXT = "http://iiif.io/api/presentation/3/context.json"
IMAGE_CONTEXT = "http://iiif.io/api/image/3/context.json"
# Presentation 3.0, 3.3.1 rights: Creative Commons or RightsStatements.org URIs.
RIGHTS = re.compile(r"https?://(creativecommons\.org/(licenses|publicdomain)/[a-z-]+/\d\.\d/"
                    r"|rightsstatements\.org/vocab/[A-Za-z-]+/1\.0/)")


def is_http_uri(s) -> bool:
    if not isinstance(s, str):
        return False
    u = urlsplit(s)
    return u.scheme in ("http", "https") and bool(u.netloc) and " " not in s


def check_language_map(v, where: str) -> None:
    """3.2: a JSON object whose keys are BCP 47 tags or "none" and values arrays of strings."""
    assert isinstance(v, dict) and v, f"{where}: not a language map: {v!r}"
    for lang, texts in v.items():
        assert lang == "none" or re.fullmatch(r"[a-zA-Z]{2,3}(-[A-Za-z0-9]{1,8})*", lang), where
        assert isinstance(texts, list) and texts and all(isinstance(t, str) for t in texts), where


def check_label_value_pairs(v, where: str) -> None:
    pairs = v if isinstance(v, list) else [v]
    for i, pair in enumerate(pairs):
        assert isinstance(pair, dict) and set(pair) == {"label", "value"}, f"{where}[{i}]"
        check_language_map(pair["label"], f"{where}[{i}].label")
        check_language_map(pair["value"], f"{where}[{i}].value")


def check_resource(r, kind: str, where: str) -> None:
    """Every resource: an HTTP(S) id and its type (3.4); label, summary language maps."""
    assert isinstance(r, dict), f"{where}: not an object"
    assert is_http_uri(r.get("id")), f"{where}: id {r.get('id')!r} is not an HTTP(S) URI"
    assert r.get("type") == kind, f"{where}: type {r.get('type')!r}, expected {kind}"
    for key in ("label", "summary"):
        if key in r:
            check_language_map(r[key], f"{where}.{key}")
    if "metadata" in r:
        assert isinstance(r["metadata"], list), where
        check_label_value_pairs(r["metadata"], f"{where}.metadata")
    if "requiredStatement" in r:
        assert isinstance(r["requiredStatement"], dict), where
        check_label_value_pairs(r["requiredStatement"], f"{where}.requiredStatement")
    if "rights" in r:
        assert isinstance(r["rights"], str) and RIGHTS.fullmatch(r["rights"]), \
            f"{where}: rights {r['rights']!r}"


def check_image_body(body, where: str) -> None:
    check_resource(body, "Image", where)
    assert isinstance(body.get("format"), str) and body["format"].startswith("image/"), where
    for k in ("width", "height"):
        if k in body:
            assert type(body[k]) is int and body[k] > 0, f"{where}.{k}"
    services = body.get("service")
    assert isinstance(services, list) and services, f"{where}: no service"
    for j, s in enumerate(services):
        assert is_http_uri(s.get("id")), f"{where}.service[{j}].id"
        assert s.get("type") == "ImageService3", f"{where}.service[{j}].type"
        assert s.get("profile") in ("level0", "level1", "level2"), f"{where}.service[{j}]"


def check_canvas(c, where: str) -> None:
    """3.2 / 5.4: a Canvas has width and height (positive integers, both or neither) and its
    items are AnnotationPages of Annotations that target it."""
    check_resource(c, "Canvas", where)
    assert "label" in c, f"{where}: a Canvas should have a label"
    assert type(c.get("width")) is int and c["width"] > 0, f"{where}.width"
    assert type(c.get("height")) is int and c["height"] > 0, f"{where}.height"
    pages = c.get("items")
    assert isinstance(pages, list) and pages, f"{where}: no annotation pages"
    for i, page in enumerate(pages):
        check_resource(page, "AnnotationPage", f"{where}.items[{i}]")
        assert isinstance(page.get("items"), list) and page["items"], f"{where}.items[{i}]"
        for j, a in enumerate(page["items"]):
            w = f"{where}.items[{i}].items[{j}]"
            check_resource(a, "Annotation", w)
            assert a.get("motivation") == "painting", f"{w}.motivation"
            target = a.get("target")
            assert isinstance(target, str) and target.split("#")[0] == c["id"], f"{w}.target"
            check_image_body(a.get("body"), f"{w}.body")


def check_manifest(m) -> None:
    """A Manifest (5.3): @context ending with the Presentation 3 context, id, type, label,
    items of at least one Canvas; all ids distinct."""
    ctx = m.get("@context")
    assert ctx == PRESENTATION_CONTEXT or (isinstance(ctx, list) and ctx[-1] == PRESENTATION_CONTEXT)
    check_resource(m, "Manifest", "manifest")
    assert "label" in m, "manifest: label is required"
    assert isinstance(m.get("items"), list) and m["items"], "manifest: no canvases"
    for i, c in enumerate(m["items"]):
        check_canvas(c, f"items[{i}]")
    ids = [c["id"] for c in m["items"]]
    ids += [p["id"] for c in m["items"] for p in c["items"]]
    ids += [a["id"] for c in m["items"] for p in c["items"] for a in p["items"]]
    assert len(ids) == len(set(ids)), "ids repeat"


def check_image_info(info: dict) -> None:
    """Image API 3.0, 5: an absolute id, type, protocol, profile, width and height."""
    assert info.get("@context") == IMAGE_CONTEXT
    assert is_http_uri(info.get("id")), f"info.json id {info.get('id')!r} is not absolute"
    assert info.get("type") == "ImageService3" and info.get("protocol") == "http://iiif.io/api/image"
    assert info.get("profile") in ("level0", "level1", "level2")
    assert type(info.get("width")) is int and type(info.get("height")) is int


def tile_urls(info: dict) -> list[str]:
    """Every tile URL a client derives from info.json (Image API 3.0, appendix A's
    algorithm: region x, y, w, h in full-size pixels, size w', h' = ceil(region / s)) and the
    full images of `sizes`."""
    base, W, H = info["id"], info["width"], info["height"]
    urls = []
    for t in info.get("tiles", []):
        tw, th = t["width"], t.get("height", t["width"])
        for s in t["scaleFactors"]:
            for y in range(0, H, th * s):
                for x in range(0, W, tw * s):
                    rw, rh = min(tw * s, W - x), min(th * s, H - y)
                    urls.append(f"{base}/{x},{y},{rw},{rh}/{math.ceil(rw / s)},"
                                f"{math.ceil(rh / s)}/0/default.jpg")
    urls += [f"{base}/full/{s['width']},{s['height']}/0/default.jpg" for s in info.get("sizes", [])]
    return urls
