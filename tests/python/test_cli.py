"""The command line (gigascroll.cli and its subcommands in gigascroll.commands): the entry
points, synth / pack / info and render end to end, and one-line errors for bad input.
(scenario and bench are tested with the scenarios and benchmarks.)"""

import json

import numpy as np
import pytest

from gigascroll import cli


def test_cli_and_module_entry_point_agree(gigascroll_cli):
    r = gigascroll_cli("--help")
    assert r.returncode == 0, r.stderr
    out_m = r.stdout
    assert "COMMAND" in out_m
    assert cli.build_parser().format_help().split()[1:4] == out_m.split()[1:4]


def test_unknown_command_fails_cleanly(gigascroll_cli):
    r = gigascroll_cli("no-such-command")
    assert r.returncode == 2
    assert "invalid choice" in r.stderr


@pytest.mark.parametrize("args,match", [
    ((), "required: COMMAND"),
    (("gallery", "--threads", "-1"), "out of range"),
    (("gallery", "--lighting", "sunny"), "invalid choice"),
    (("pack", "--no-such-option"), "required"),
    (("render", "-o", "x.png", "--photons", "many"), "invalid int value"),
])
def test_usage_errors_are_one_line(args, match, gigascroll_cli):
    """A usage error is one line on stderr naming the problem and --help, exit code 2."""
    r = gigascroll_cli(*args)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and match in lines[0] and "--help" in lines[0], r.stderr


def test_cli_synth_pack_info(tmp_path, capsys, gigascroll_cli):
    tif = tmp_path / "s.tif"
    r = gigascroll_cli("synth", "--width", 900, "--height", 130, "-o", tif)
    assert r.returncode == 0, r.stderr
    r = gigascroll_cli("synth", "--width", 900, "--height", 130, "-o", tif)
    assert r.returncode == 2 and "already exists" in r.stderr and "Traceback" not in r.stderr
    r = gigascroll_cli("pack", tif, tif, "-o", tmp_path / "p", "--tile-size", 32, "--border", 2,
                "--codec", "zstd")
    assert r.returncode == 0, r.stderr
    assert "Mpixel/s" in r.stdout and "s-2" in r.stdout  # second copy renamed
    r = gigascroll_cli("info", tmp_path / "p", "--verify")
    assert r.returncode == 0 and "all checksums match" in r.stdout
    r = gigascroll_cli("info", tmp_path / "p", "--json")
    m = json.loads(r.stdout)
    assert m["codec"] == "zstd" and len(m["paintings"]) == 2
    for args, msg in [(("pack", tmp_path / "nope.tif", "-o", tmp_path / "q"), "no such"),
                      (("pack", tif, "-o", tmp_path / "q", "--codec", "png"), "codec"),
                      (("pack", tif, "-o", tmp_path / "q", "--tile-size", 8), "border"),
                      (("pack", tif, "-o", tmp_path / "p"), "already exists"),
                      (("info", tmp_path), "missing manifest"),
                      (("synth", "--width", 0, "-o", tmp_path / "z.tif"), "positive")]:
        code = cli.main([str(a) for a in args])  # in-process: same parser, faster
        err = capsys.readouterr().err
        assert code == 2, (args, err)
        assert msg in err and "Traceback" not in err, (args, err)
    assert not (tmp_path / "q").exists()


def test_render_command_writes_exr_and_png(tmp_path, gigascroll_cli):
    oiio = pytest.importorskip("OpenImageIO")
    out = tmp_path / "cornell.exr"
    r = gigascroll_cli("render", "cornell", "-o", out, "--width", 32, "--height", 32, "--photons", 20000)
    assert r.returncode == 0, r.stderr
    assert "gather" in r.stdout and "photons" in r.stdout
    img = oiio.ImageInput.open(str(out))
    data = img.read_image("float")
    img.close()
    assert data.shape == (32, 32, 3) and np.isfinite(data).all() and data.mean() > 0.05
    png = tmp_path / "cornell.png"
    r = gigascroll_cli("render", "cornell", "-o", png, "--width", 16, "--height", 16, "--photons", 5000)
    assert r.returncode == 0 and png.stat().st_size > 0


def test_render_command_progressive_is_the_api_render(tmp_path, gigascroll_cli):
    """--progressive / --passes / --disc reach the renderer: the CLI's image is the API's."""
    oiio = pytest.importorskip("OpenImageIO")
    import gigascroll as g
    out = tmp_path / "p.exr"
    r = gigascroll_cli("render", "cornell", "-o", out, "--width", 24, "--height", 24,
                       "--photons", 4000, "--progressive", "--passes", 3, "--seed", 5)
    assert r.returncode == 0, r.stderr
    assert "progressive 3 passes" in r.stdout
    img = oiio.ImageInput.open(str(out))
    got = img.read_image("float")
    img.close()
    scene, cam = g.builtin_scene("cornell", resolution=(24, 24))
    want = g.render(scene, cam, photons=4000, radius=0.02, progressive=True, passes=3, seed=5)
    np.testing.assert_array_equal(got, want)
    sphere = g.render(scene, cam, photons=4000, radius=0.02, progressive=True, passes=3, seed=5,
                      disc=False)
    assert not np.array_equal(sphere, want)  # the default (disc) was the one the CLI used


def test_render_command_camera_on_a_builtin_scene(tmp_path, gigascroll_cli):
    """--camera moves a built-in scene's camera (it applied to --room only, and was ignored):
    the CLI's image is the API's render through Camera(eye, target, +y, fov), and not the
    scene's own view."""
    oiio = pytest.importorskip("OpenImageIO")
    import gigascroll as g
    out = tmp_path / "c.exr"
    r = gigascroll_cli("render", "cornell", "-o", out, "--width", 24, "--height", 20,
                       "--photons", 4000, "--camera", "0.3,0.2,3.5,0,-0.1,0,35", "--seed", 3)
    assert r.returncode == 0, r.stderr
    img = oiio.ImageInput.open(str(out))
    got = img.read_image("float")
    img.close()
    scene, own = g.builtin_scene("cornell", resolution=(24, 20))
    cam = g.Camera((0.3, 0.2, 3.5), (0, -0.1, 0), (0, 1, 0), 35.0, (24, 20))
    want = g.render(scene, cam, photons=4000, radius=0.02, spp=4, light_samples=16, seed=3)
    np.testing.assert_array_equal(got, want)
    assert not np.array_equal(got, g.render(scene, own, photons=4000, radius=0.02, spp=4,
                                            light_samples=16, seed=3))


@pytest.mark.parametrize("args,match", [
    (["render", "cornell", "-o", "x.exr", "--progressive", "--passes", "0"], "passes"),
    (["render", "cornell", "-o", "x.exr", "--progressive", "--spp", "4"], "spp"),
    (["render", "cornell", "-o", "x.exr", "--progressive", "--time-budget", "nan"], "budget"),
    (["render", "kitchen", "-o", "x.exr"], "invalid choice"),
    (["render", "cornell", "-o", "x.exr", "--radius", "-1"], "radius"),
    (["render", "cornell", "-o", "x.bmpx"], "format"),
    (["render", "cornell", "-o", "/nonexistent-dir/x.exr", "--width", "8", "--height", "8",
      "--photons", "100"], "directory"),
    (["render", "cornell", "-o", "x.exr", "--camera", "nan,0,0,0,0,1"], "finite numbers"),
    (["render", "cornell", "-o", "x.exr", "--lighting", "full"], "--lighting applies to --room"),
    (["render", "cornell", "-o", "x.exr", "--pack", "p"], "--pack applies to --room"),
    (["render", "cornell", "-o", "x.exr", "--camera", "0,1,0,0,1,0"], "must differ"),
    (["render", "cornell", "-o", "x.exr", "--camera", "0,5,0,0,0,0", "--photons", "100"], "parallel"),
])
def test_render_command_bad_input(args, match, tmp_path, gigascroll_cli):
    r = gigascroll_cli(*args, cwd=tmp_path)
    assert r.returncode == 2
    assert match in r.stderr
    assert "Traceback" not in r.stderr
    assert not (tmp_path / "x.exr").exists()
