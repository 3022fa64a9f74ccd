"""H.264 videos: codec, pixel format, sizes, content, errors, and playback in a browser."""

from __future__ import annotations

import functools
import http.server
import threading

import numpy as np
import pytest

from havln_mj.errors import HavlnError, InvalidArgumentError, MissingDataError
from havln_mj.render.video import VideoWriter, probe


def _frames(n, width, height):
    """A bar growing left to right: red on blue."""
    for k in range(n):
        frame = np.zeros((height, width, 3), np.uint8)
        frame[...] = (0, 0, 200)
        frame[:, : (k + 1) * width // n] = (220, 30, 30)
        yield frame


def test_writes_h264_yuv420p_with_every_frame(tmp_path):
    path = tmp_path / "sub" / "walk.mp4"
    with VideoWriter(path, fps=12, size=(64, 48)) as video:
        for frame in _frames(24, 64, 48):
            video.write(frame)
    assert video.closed and video.frames == 24
    info = probe(path)
    assert info["codec"] == "h264" and info["pixel_format"] == "yuv420p"
    assert info["size"] == (64, 48) and info["fps"] == 12.0 and info["frames"] == 24
    assert info["duration_s"] == pytest.approx(2.0, abs=0.1)
    assert list(path.parent.iterdir()) == [path]  # no partial file left beside it


def test_odd_sizes_are_padded_not_rescaled(tmp_path):
    import imageio_ffmpeg

    path = tmp_path / "odd.mp4"
    frames = list(_frames(6, 65, 47))
    with VideoWriter(path, fps=5, size=(65, 47)) as video:
        for frame in frames:
            video.write(frame)
    assert probe(path)["size"] == (66, 48)
    reader = imageio_ffmpeg.read_frames(str(path))
    next(reader)
    decoded = [np.frombuffer(b, np.uint8).reshape(48, 66, 3) for b in reader]
    # The picture is where it was written; the padding repeats the last column and row.
    for got, want in zip(decoded, frames, strict=True):
        assert np.abs(got[:47, :65].astype(int) - want).mean() < 6
        assert np.abs(got[:, 65].astype(int) - got[:, 64]).mean() < 6
        assert np.abs(got[47].astype(int) - got[46]).mean() < 6


def test_bad_input_names_the_path(tmp_path):
    path = tmp_path / "bad.mp4"
    with pytest.raises(InvalidArgumentError, match=r"must end in \.mp4"):
        VideoWriter(tmp_path / "bad.avi", fps=10, size=(8, 8))
    with pytest.raises(InvalidArgumentError, match=r"bad\.mp4: fps"):
        VideoWriter(path, fps=0, size=(8, 8))
    with pytest.raises(InvalidArgumentError, match=r"bad\.mp4: size"):
        VideoWriter(path, fps=10, size=(8, -2))
    video = VideoWriter(path, fps=10, size=(8, 8))
    with pytest.raises(InvalidArgumentError, match=r"bad.mp4: frames must be uint8.*\(8, 8, 3\)"):
        video.write(np.zeros((8, 8, 3), np.float32))
    with pytest.raises(InvalidArgumentError, match=r"got uint8 \(8, 9, 3\)"):
        video.write(np.zeros((8, 9, 3), np.uint8))
    video.write(np.zeros((8, 8, 3), np.uint8))
    video.close()
    with pytest.raises(HavlnError, match="write\\(\\) after close\\(\\)"):
        video.write(np.zeros((8, 8, 3), np.uint8))
    with pytest.raises(MissingDataError):
        probe(tmp_path / "none.mp4")


def test_nothing_is_left_at_the_path_when_writing_fails(tmp_path):
    path = tmp_path / "crash.mp4"
    with pytest.raises(RuntimeError, match="boom"), VideoWriter(path, 10, (16, 16)) as video:
        video.write(np.zeros((16, 16, 3), np.uint8))
        raise RuntimeError("boom")
    with pytest.raises(HavlnError, match="no frames were written"):
        VideoWriter(path, 10, (16, 16)).close()
    assert list(tmp_path.iterdir()) == []


def test_a_browser_plays_it(tmp_path):
    """Chromium's <video> element decodes the file and reports its duration."""
    from havln_mj.annotator.browser import browser_paths, headless_chromium

    pytest.importorskip("selenium", reason="selenium comes with .[dev]")
    try:
        browser_paths()
    except MissingDataError as exc:
        pytest.skip(str(exc))
    with VideoWriter(tmp_path / "clip.mp4", fps=10, size=(96, 72)) as video:
        for frame in _frames(15, 96, 72):
            video.write(frame)
    (tmp_path / "index.html").write_text('<video id="v" src="clip.mp4" muted></video>')
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(tmp_path))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        with headless_chromium() as browser:
            browser.get(f"http://127.0.0.1:{server.server_address[1]}/index.html")
            state = browser.execute_async_script(
                """const done = arguments[arguments.length - 1];
                const v = document.getElementById('v');
                const report = () => done({duration: v.duration, width: v.videoWidth,
                                           error: v.error && v.error.code});
                if (v.readyState >= 1 || v.error) report();
                v.addEventListener('loadedmetadata', report);
                v.addEventListener('error', report);"""
            )
    finally:
        server.shutdown()
        server.server_close()
    assert state["error"] is None
    assert state["duration"] == pytest.approx(1.5, abs=0.1) and state["width"] == 96
