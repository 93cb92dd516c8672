"""Fuzz: `gigascroll light --exhibition` with random companions (a show, a pack, a
directory that is no show, a file, nothing; --room, --lights, -o, the figures' options):
exit 0 with a whole report, or exit 2 with one line and no report; never a traceback, a
crash or a hang. Cases run in forked children (fuzz_support)."""

from __future__ import annotations

import itertools

import pytest
from fuzz_support import CASES, cli_message_ok, count_case, fork_worker, fuzz_settings  # noqa: F401
from hypothesis import given
from hypothesis import strategies as st

from test_exhibit import SHOW, write_images

_counter = itertools.count()


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    from gigascroll.cli import main
    d = tmp_path_factory.mktemp("fuzz-light-show")
    write_images(d)
    (d / "show.toml").write_text(SHOW)
    assert main(["exhibit", "build", str(d / "show.toml"), "-o", str(d / "show"), "--no-bake",
                 "--no-iiif"]) == 0
    (d / "empty").mkdir()
    (d / "lights.json").write_text("[]")
    return d


TARGET = st.sampled_from(["show", "show/paintings.pack", "empty", "show.toml", "nope", ""])
EXTRA = st.lists(st.sampled_from([
    ["--room", "hall"], ["--room", "scroll"], ["--lights", "lights.json"], ["PACK"],
    ["--category", "medium"], ["--category", "x"], ["--hours-per-day", "nan"],
    ["--days-per-year", "400"], ["--targets", "total"], ["--samples", "1"],
    ["--lighting", "full"], ["-o", "OUT"], ["-o", "show"], ["-o", ""]]), max_size=3)


@fuzz_settings(15)
@given(target=TARGET, extra=EXTRA)
def test_random_light_exhibition(fork_worker, files, target, extra):
    count_case("light --exhibition")
    n = next(_counter)
    out = files / f"out{n}"
    subst = {"PACK": str(files / "show" / "paintings.pack"), "OUT": str(out)}
    argv = ["light", "--exhibition", str(files / target) if target else "",
            "--photons", "2000", "--samples", "8", "--threads", "1"]
    argv += [subst.get(a, a) for e in extra for a in e]
    o = fork_worker.run({"kind": "cli", "argv": argv, "cwd": str(files)}, timeout=120)
    problem = cli_message_ok(o)
    assert problem is None, f"{problem}: {argv}\n{o.describe()}"
    outs = [e[1] for e in extra if e[0] == "-o"]
    if o.code == 0:
        where = files / "show-light" if not outs else out if outs[-1] == "OUT" else None
        assert where is not None and (where / "light.json").is_file() \
            and (where / "index.html").is_file(), outs
    elif outs and outs[-1] == "OUT":
        assert not out.exists()
    assert (files / "show" / "exhibition.json").is_file()  # never replaced by a report
