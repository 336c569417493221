"""Point and image files: round trips, the text format UTK/PSA read, atomic writes."""

import os

import numpy as np
import pytest

from clsamp import files
from clsamp.errors import InvalidArgumentError


@pytest.mark.parametrize("suffix", [".txt", ".dat", ".npy"])
@pytest.mark.parametrize("shape", [(7, 2), (3, 5, 3), (4, 1), (1, 6, 2)])
def test_points_round_trip_exactly(tmp_path, suffix, shape):
    points = np.random.default_rng(1).random(shape)
    path = files.save_points(tmp_path / f"p{suffix}", points)
    np.testing.assert_array_equal(files.load_points(path), points)


def test_text_format_is_one_point_a_line(tmp_path):
    path = files.save_points(tmp_path / "p.txt", np.array([[0.25, 0.5], [0.125, 0.75]]))
    assert path.read_text().splitlines() == ["0.25 0.5", "0.125 0.75"]


def test_a_batch_of_one_set_keeps_its_axis_in_text():
    # (1, n, d) was written like (n, d) and read back without its first axis; a batch now
    # starts with "# r sets", which must match the sets that follow
    text = files.format_points(np.full((1, 2, 2), 0.5))
    assert text.splitlines()[0] == "# 1 set" and files.parse_points(text).shape == (1, 2, 2)
    assert files.parse_points("# a comment\n0.1 0.2\n").shape == (1, 2)
    with pytest.raises(InvalidArgumentError, match="declares 2 sets and holds 1"):
        files.parse_points("# 2 sets\n0.1 0.2\n")


def test_reads_utk_style_text(tmp_path):
    path = tmp_path / "utk.dat"
    path.write_text("0.1\t0.2\n0.3 0.4\n\n")
    np.testing.assert_array_equal(files.load_points(path), [[0.1, 0.2], [0.3, 0.4]])


def test_malformed_text_names_the_line(tmp_path):
    path = tmp_path / "bad.txt"
    path.write_text("0.1 0.2\n0.3 oops\n")
    with pytest.raises(InvalidArgumentError, match="line 2"):
        files.load_points(path)
    path.write_text("0.1 0.2\n0.3\n")
    with pytest.raises(InvalidArgumentError, match="different dimensions"):
        files.load_points(path)
    path.write_text("0.1 1.5\n")
    with pytest.raises(InvalidArgumentError, match=r"\[0, 1\)"):
        files.load_points(path)


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path):
    path = tmp_path / "p.txt"
    files.save_points(path, np.array([[0.5, 0.5]]))
    before = path.read_bytes()
    with pytest.raises(RuntimeError):
        with files.atomic_path(path) as tmp:
            tmp.write_text("half a fi")
            raise RuntimeError("crash in the middle")
    assert path.read_bytes() == before
    assert os.listdir(tmp_path) == ["p.txt"]


def test_invalid_points_are_not_written(tmp_path):
    with pytest.raises(InvalidArgumentError):
        files.save_points(tmp_path / "p.txt", np.array([[0.5, np.nan]]))
    assert not (tmp_path / "p.txt").exists()


def test_exr_round_trip_with_header(tmp_path):
    image = np.random.default_rng(2).random((6, 9, 3)).astype(np.float32)
    files.write_exr(tmp_path / "i.exr", image, {"sampler": "jittered", "spp": 16, "seed": 3})
    back, header = files.read_exr(tmp_path / "i.exr", with_header=True)
    np.testing.assert_array_equal(back, image)
    assert header["sampler"] == "jittered" and header["spp"] == "16" and header["seed"] == "3"
    gray = image[:, :, 0]
    files.write_exr(tmp_path / "g.exr", gray)
    np.testing.assert_array_equal(files.read_exr(tmp_path / "g.exr"), gray)


def test_png_preview(tmp_path):
    path = files.write_png(tmp_path / "i.png", np.linspace(0, 2, 30, dtype=np.float32).reshape(5, 6))
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert files.tone_map(np.array([[2.0, 0.0]]))[0, 0] == 255


def test_names_up_to_the_file_systems_limit_are_written_and_longer_ones_refused(tmp_path):
    # the temporary name was the target's plus 15 characters: 240-255 failed after the work,
    # and past 255 check_output itself raised OSError (ENAMETOOLONG)
    path = files.save_points(tmp_path / ("a" * 244 + ".txt"), np.full((2, 2), 0.5))
    assert files.load_points(path).shape == (2, 2)
    with pytest.raises(InvalidArgumentError, match="a name of 304 bytes in it, longer than the 255"):
        files.check_output(tmp_path / ("a" * 300 + ".txt"), "'-o'")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a" * 244 + ".txt"]


def test_writing_through_a_link_writes_its_target_and_keeps_the_link(tmp_path):
    (tmp_path / "target.txt").write_text("old")
    (tmp_path / "link.txt").symlink_to("target.txt")
    files.write_text(tmp_path / "link.txt", "new")
    assert (tmp_path / "link.txt").is_symlink() and (tmp_path / "target.txt").read_text() == "new"


def test_grey_png_levels_and_exr_refusals(tmp_path):
    import matplotlib.image as mpimg
    grey = np.arange(256, dtype=np.uint8).reshape(16, 16)
    back = mpimg.imread(files.write_png(tmp_path / "g.png", grey, tone=False))
    assert np.array_equal(np.round(back[:, :, 0] * 255).astype(np.uint8), grey)   # 24 levels moved by one
    with pytest.raises(InvalidArgumentError, match="'image' must be uint8, got float64"):
        files.write_png(tmp_path / "f.png", np.full((2, 2), 0.8), tone=False)   # written black before
    for image, header, match in ((np.zeros((0, 5)), None, "must hold pixels"),
                                 (np.full((2, 2), 1e39), None, "beyond float32's range"),
                                 (np.ones((2, 2)), {"channels": "x"}, "'header' key 'channels'")):
        with pytest.raises(InvalidArgumentError, match=match):
            files.write_exr(tmp_path / "e.exr", image, header=header)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["g.png"]


def test_json_documents_are_standard_json(tmp_path):
    import json
    document = {"rate": [float("nan"), np.float64(-np.inf)], "n": np.int64(3)}
    path = files.write_json(tmp_path / "d.json", document)
    text = path.read_text()
    assert json.loads(text, parse_constant=pytest.fail) == {"rate": ["nan", "-inf"], "n": 3}



def test_a_name_of_multibyte_characters_within_the_limit_is_written(tmp_path):
    # the temporary name was cut in characters, 127 of 3 bytes each: past 255 bytes after the work
    name = "\u70b9" * 80 + ".txt"                     # 244 bytes
    files.save_points(tmp_path / name, np.full((2, 2), 0.5))
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


def test_a_pipe_or_a_device_is_written_into_not_replaced(tmp_path):
    # os.replace swapped a regular file in for them: as root, '-o /dev/null' replaced /dev/null
    import threading
    fifo = tmp_path / "pipe.txt"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()), daemon=True)
    reader.start()
    files.write_text(fifo, "through the pipe")
    reader.join(10)
    assert got == [b"through the pipe"] and fifo.is_fifo()
    if os.geteuid() == 0:
        null = tmp_path / "null.txt"
        os.mknod(null, 0o666 | 0o020000, os.makedev(1, 3))     # a character device: /dev/null
        files.write_text(null, "gone")
        assert null.is_char_device()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]    # no temporary left


def test_links_that_lead_nowhere_writable_are_refused_before_any_work(tmp_path):
    (tmp_path / "afile").write_text("")
    (tmp_path / "dangling.txt").symlink_to("afile/f.txt")       # its target's folder is a file
    (tmp_path / "loop.txt").symlink_to("loop2")
    (tmp_path / "loop2").symlink_to("loop.txt")
    with pytest.raises(InvalidArgumentError, match="dangling.txt'"):
        files.check_output(tmp_path / "dangling.txt")
    with pytest.raises(InvalidArgumentError, match="symbolic links"):
        files.check_output(tmp_path / "loop.txt")


@pytest.mark.parametrize("image", [np.zeros((2, 2, 2, 3), np.uint8), np.zeros((4, 4, 2), np.uint8),
                                   np.zeros(5, np.uint8), np.zeros((0, 3), np.uint8)])
def test_a_png_of_uint8_values_checks_its_shape(tmp_path, image):
    # (2, 2, 2, 3) was written as a 2 x 2 image, half the values lost; the others failed in matplotlib
    with pytest.raises(InvalidArgumentError, match="'image' must"):
        files.write_png(tmp_path / "p.png", image, tone=False)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("header, match", [
    ({"tiles": "x"}, "'tiles' is empty or the file's own"),      # dropped from the file
    ({"version": 2}, "'version'"), ({"chunkCount": 1}, "'chunkCount'"), ({"": 1}, "'' is empty"),
    ({"chromaticities": "x"}, "does not fit an OpenEXR header: .*'chromaticities'"),
    ([("a", 1)], "'header' must be a dict"),
])
def test_exr_header_keys_the_file_cannot_hold_as_text_are_refused(tmp_path, header, match):
    with pytest.raises(InvalidArgumentError, match=match):
        files.write_exr(tmp_path / "e.exr", np.ones((2, 2)), header=header)
    assert list(tmp_path.iterdir()) == []


def test_json_safe_writes_booleans_and_refuses_keys_that_collide():
    assert files.json_safe({"x": np.bool_(False)}) == {"x": False}      # was the text "False"
    with pytest.raises(InvalidArgumentError, match="keys 1 and .1. of a dict write as one JSON key"):
        files.json_safe({1: "a", "1": "b"})
