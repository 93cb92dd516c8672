"""The README's "Bring your own painting" start runs as written: its shell commands (each
`gigascroll ...` line of the section's ```sh blocks) and its exhibition file (the ```toml
block, saved as show.toml) on a painting of the size the README names, scaled down 10x per
axis (600 x 80 px: the same aspect, so the file's 300 x 40 cm still agrees with it).

The only changes to the commands are listed in SMALLER (a smaller walk: the README's takes a
minute); `serve` runs until stopped, so its line is only parsed (its options must exist).
References: the pack against the image's size, the still against the painting's colour (a
painting of one known colour, `--look-at` centres it), the walk's files where the README says
they land, the show's painting at its physical size."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from gigascroll.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[2]
SMALLER = {"--eye 720x792 --seconds 3": "--eye 48x48 --seconds 0.2 --no-video"}
COLOUR = (40, 70, 200)  # the painting: one blue, so a still shows where it is


def section() -> str:
    text = (ROOT / "README.md").read_text()
    start = text.index("## Bring your own painting")
    return text[start:text.index("\n## ", start + 1)]


def commands() -> list[str]:
    """The section's `gigascroll ...` command lines, in order, comments removed."""
    lines = []
    for block in re.findall(r"```sh\n(.*?)\n```", section(), re.S):
        for line in block.splitlines():
            line = line.split("#")[0].strip()
            if line.startswith("gigascroll "):
                lines.append(line)
    return lines


def test_the_start_is_on_the_first_screen():
    """What gigascroll does, one picture, and the start, before the first build section."""
    text = (ROOT / "README.md").read_text()
    first = text[:text.index("\n## ", text.index("## Bring your own painting") + 1)]
    assert first.count("![") == 1 and "gigascroll pack" in first
    assert len(commands()) >= 6 and re.search(r"```toml\n", section())


@pytest.fixture(scope="module")
def ran(tmp_path_factory):
    d = tmp_path_factory.mktemp("readme-start")
    Image.fromarray(np.full((80, 600, 3), COLOUR, np.uint8)).save(d / "my_painting.png")
    toml = re.search(r"```toml\n(.*?)\n```", section(), re.S).group(1)
    (d / "show.toml").write_text(toml)
    import os
    cwd = os.getcwd()
    os.chdir(d)
    codes = {}
    try:
        for line in commands():
            for long, short in SMALLER.items():
                line = line.replace(long, short)
            argv = shlex.split(line)[1:]
            if argv[0] == "serve":
                codes[line] = build_parser().parse_args(argv)
                continue
            codes[line] = main(argv)
    finally:
        os.chdir(cwd)
    return d, codes


def test_every_command_succeeds(ran):
    _, codes = ran
    failed = {k: v for k, v in codes.items() if isinstance(v, int) and v != 0}
    assert not failed, failed
    assert sum(1 for v in codes.values() if hasattr(v, "func")) == 2  # the two serve lines


def _centre(path: Path) -> np.ndarray:
    a = np.asarray(Image.open(path).convert("RGB"), np.float64)
    h, w = a.shape[:2]
    return a[h // 2 - 2:h // 2 + 3, w // 2 - 2:w // 2 + 3].reshape(-1, 3).mean(axis=0)


def test_what_the_commands_made(ran):
    from gigascroll.pack import TilePack
    d, _ = ran
    pack = TilePack(d / "my_painting.pack")
    assert [(p.width, p.height) for p in pack.paintings] == [(600, 80)]
    # Both stills look at the painting: its blue at the centre (lit and exposed, so only
    # the hue is checked: blue well above red and green).
    for still in ("still.png", "mine.png"):
        r, g, b = _centre(d / still)
        assert b > 1.5 * r and b > 1.3 * g, (still, r, g, b)
    # The walk's video, frames and report land next to the pack, as the README says.
    walk = d / "my_painting-walk"
    assert (walk / "report.md").is_file() and any((walk / "frames").iterdir())
    # The show's light report lands next to the show, its painting named by its title.
    import json
    report = json.loads((d / "show-light" / "light.json").read_text())
    assert [p["name"] for p in report["paintings"]] == ["My painting"]
    # The show hangs the painting at its real size.
    from gigascroll.exhibit.show import open_show
    slot = open_show(d / "show").room.paintings[0]
    assert (slot.width_m, slot.height_m) == (3.0, 0.4)
