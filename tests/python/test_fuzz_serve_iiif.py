"""Fuzz: random request paths under serve's /iiif/ (the show's IIIF folder): 200 only for a
file of the folder, else 404 (or 400 for a malformed request); never a 5xx or a file from
outside the folder."""

from __future__ import annotations

from fuzz_support import fuzz_settings
from hypothesis import given
from hypothesis import strategies as st
from test_serve_show_iiif import fetch, served  # noqa: F401 (the fixture)


PARTS = st.sampled_from(["..", ".", "", "red-study", "info.json", "manifest.json", "full",
                         "%2e%2e", "%2F", "a\\b", "0,0,64,48", "max", "0", "default.jpg",
                         "x" * 300, "%00", "~", "exhibition.json", ".mark"])


@fuzz_settings(40)
@given(parts=st.lists(PARTS, min_size=1, max_size=6))
def test_random_iiif_paths(served, parts):
    """Any path: 200 only for a file inside the IIIF folder, else 404; never a 5xx."""
    _, url = served
    path = "/".join(parts)
    status, _, body = fetch(f"{url}/iiif/{path}")
    assert status in (200, 404, 400), (path, status)
    if status == 200:  # only the folder's JSON and JPEG files
        assert body[:1] == b"{" or body[:2] == b"\xff\xd8", path
