"""`gigascroll light --exhibition SHOW`: the conservators' figures of a built show, its
paintings named by title and its wall labels left out.

References: each painting's mean direct illuminance by Lambert's polygon formula (the
report's analytic column) against the 200 lx the show's default lights are solved for; the
measured grid's mean (direct plus interreflections) bounded by it."""

from __future__ import annotations

import json

import pytest

from gigascroll.cli import main

from test_exhibit import SHOW, write_images


@pytest.fixture(scope="module")
def show(tmp_path_factory):
    d = tmp_path_factory.mktemp("light-show")
    write_images(d)
    (d / "show.toml").write_text(SHOW)
    assert main(["exhibit", "build", str(d / "show.toml"), "-o", str(d / "show"), "--no-bake",
                 "--no-iiif"]) == 0
    return d


def test_a_shows_figures(show, capsys):
    capsys.readouterr()
    assert main(["light", "--exhibition", str(show / "show"), "--samples", "16",
                 "--photons", "20000", "--lighting", "full", "--light-samples", "64"]) == 0
    out = capsys.readouterr().out
    report = show / "show-light"  # next to the show, as for a pack
    d = json.loads((report / "light.json").read_text())
    assert [p["name"] for p in d["paintings"]] == ["Red study", "Blue study"]  # no labels
    assert d["exhibition"] == str(show / "show") and d["pack"].endswith("paintings.pack")
    # Each light is solved for 200 lx of its own direct light on its painting; the other
    # painting's light spills some onto it (spill only adds).
    for p in d["paintings"]:
        assert 198 <= p["direct_mean_lux_analytic"] <= 250
        # Direct plus the walls' bounce: at least the direct light, within 2x of it.
        assert 0.95 * p["direct_mean_lux_analytic"] <= p["mean_lux"] <= 400
        assert (report / p["map"]).is_file()
    assert "Red study: min" in out and f"wrote {report}/" in out


@pytest.mark.parametrize("argv, message", [
    (["--lights", "x.json"], "--exhibition brings its own lights"),
    (["--room", "hall"], "--exhibition brings its own room"),
    (["PACK"], "--exhibition brings its own pack"),
])
def test_misuse_is_one_line(show, capsys, argv, message):
    argv = [str(show / "show" / "paintings.pack") if a == "PACK" else a for a in argv]
    capsys.readouterr()
    assert main(["light", "--exhibition", str(show / "show"), *argv]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and message in err[0], err


def test_neither_pack_nor_show(capsys):
    assert main(["light"]) == 2
    assert "give a PACK (with --room) or --exhibition SHOW" in capsys.readouterr().err
