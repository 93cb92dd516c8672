"""room.assets' regular-file checks take paths only: an int is an open file descriptor to
os.stat and os.open (0 is stdin), so it is refused before either sees it."""

import pytest

from gigascroll.room.assets import check_regular, read_regular


@pytest.mark.parametrize("path", [0, 1, 2**64, -1, 1.5, None, ["a"]])
def test_a_path_that_is_not_a_path_is_a_type_error(path):
    with pytest.raises(TypeError, match="a path must be"):
        check_regular(path, "the file")
    with pytest.raises(TypeError, match="a path must be"):
        read_regular(path, "the file", 1 << 20)


def test_paths_of_every_kind_are_read(tmp_path):
    f = tmp_path / "a.bin"
    f.write_bytes(b"abc")
    for path in (f, str(f), bytes(f)):
        assert check_regular(path, "the file").st_size == 3
        assert read_regular(path, "the file", 1 << 20) == b"abc"
    with pytest.raises(OSError, match="not a regular file"):
        check_regular(tmp_path, "the folder")
