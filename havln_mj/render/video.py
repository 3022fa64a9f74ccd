"""H.264 MP4 videos that browsers, GitHub and editors play.

Frames go to the ``ffmpeg`` binary that the ``imageio-ffmpeg`` package ships, encoded with
``libx264`` in ``yuv420p`` (the only chroma layout every H.264 player decodes), x264's
``veryfast`` preset (on rendered 640×480 views it encodes faster than they render, into smaller
files than MPEG-4 Part 2 at higher fidelity) and the index at the front of the file
(``+faststart``: a browser starts playing before the whole file has arrived). H.264 in
``yuv420p`` needs even frame sizes: an odd width or height is padded by one pixel, repeating
the last column or row, rather than rescaled.

The file appears at its path only once the writer is closed without error; until then it is
written beside it under a temporary name, so an interrupted run leaves no truncated video.

Example:
    >>> with VideoWriter(out / "walk.mp4", fps=10, size=(128, 96)) as video:  # doctest: +SKIP
    ...     for rgb in frames:
    ...         video.write(rgb)
"""

from __future__ import annotations

import contextlib
import math
import numbers
import os
from pathlib import Path

import numpy as np

from havln_mj.errors import ClosedError, InvalidArgumentError, OutputError

CODEC = "libx264"
PIXEL_FORMAT = "yuv420p"
DEFAULT_QUALITY = 7
"""imageio-ffmpeg's 1–10 scale; 7 maps to x264's CRF 15 (about 42 dB PSNR on rendered views)."""
PRESET = "veryfast"  # x264 speed preset: several times faster than "medium", files as small


def _even(n: int) -> int:
    return n + (n % 2)


class VideoWriter:
    """Writes RGB frames to an H.264 MP4 file.

    Args:
        path: The ``.mp4`` file to write (its folder is created).
        fps: Frames per second (positive).
        size: ``(width, height)`` of every frame, in pixels.
        quality: imageio-ffmpeg's quality, 1 (smallest file) to 10 (best).

    Raises:
        InvalidArgumentError: A path not ending in ``.mp4``, a non-positive or non-finite
            ``fps``, a size that is not two positive ints, or a quality outside 1–10.
        HavlnError: The encoder could not start (the message names the path).
    """

    def __init__(
        self,
        path: Path | str,
        fps: float,
        size: tuple[int, int],
        *,
        quality: float = DEFAULT_QUALITY,
    ) -> None:
        self.path = Path(path)
        if self.path.suffix.lower() != ".mp4":
            raise InvalidArgumentError(f"video path must end in .mp4, got {str(self.path)!r}")
        if not (isinstance(fps, numbers.Real) and math.isfinite(fps) and fps > 0):
            raise InvalidArgumentError(f"{self.path}: fps must be a positive number, got {fps!r}")
        if not (
            isinstance(size, tuple | list)
            and len(size) == 2
            and all(isinstance(n, numbers.Integral) and n > 0 for n in size)
        ):
            raise InvalidArgumentError(
                f"{self.path}: size must be (width, height), two positive ints, got {size!r}"
            )
        if not (isinstance(quality, numbers.Real) and 1 <= quality <= 10):
            raise InvalidArgumentError(f"{self.path}: quality must be in [1, 10], got {quality!r}")
        import imageio_ffmpeg

        self.fps = float(fps)
        self.width, self.height = int(size[0]), int(size[1])
        self.frames = 0
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._partial = self.path.with_name(f".{self.path.stem}.partial.mp4")
        self._encoder = imageio_ffmpeg.write_frames(
            str(self._partial),
            (_even(self.width), _even(self.height)),
            fps=self.fps,
            codec=CODEC,
            pix_fmt_out=PIXEL_FORMAT,
            quality=float(quality),
            macro_block_size=1,  # odd sizes are padded here, never rescaled
            ffmpeg_log_level="error",
            output_params=["-preset", PRESET, "-movflags", "+faststart"],
        )
        try:
            self._encoder.send(None)  # starts ffmpeg
        except (OSError, RuntimeError) as exc:
            self._encoder = None
            raise OutputError(f"{self.path}: cannot start the H.264 encoder ({exc})") from None

    @property
    def closed(self) -> bool:
        """Whether the writer has been closed."""
        return self._encoder is None

    def write(self, rgb: np.ndarray) -> None:
        """Appends one frame.

        Args:
            rgb: ``uint8`` array of shape ``(height, width, 3)``, top row first.

        Raises:
            InvalidArgumentError: A frame of another shape or dtype.
            HavlnError: The writer is closed, or the encoder stopped (naming the path).
        """
        if self._encoder is None:
            raise ClosedError(f"{self.path}: write() after close()")
        frame = np.asarray(rgb)
        want = (self.height, self.width, 3)
        if frame.shape != want or frame.dtype != np.uint8:
            raise InvalidArgumentError(
                f"{self.path}: frames must be uint8 arrays of shape {want} (height, width, RGB), "
                f"got {frame.dtype} {frame.shape}"
            )
        pad = ((0, self.height % 2), (0, self.width % 2), (0, 0))
        if any(p[1] for p in pad):
            frame = np.pad(frame, pad, mode="edge")
        try:
            self._encoder.send(np.ascontiguousarray(frame))
        except (OSError, RuntimeError) as exc:
            self._abort()
            raise OutputError(f"{self.path}: the H.264 encoder stopped ({exc})") from None
        self.frames += 1

    def close(self) -> None:
        """Finishes the file and moves it to its path (a no-op when already closed).

        Raises:
            HavlnError: No frame was written (nothing is left at the path), or the encoder
                failed to finish.
        """
        if self._encoder is None:
            return
        if self.frames == 0:
            self._abort()
            raise OutputError(f"{self.path}: no frames were written; no video was made")
        encoder, self._encoder = self._encoder, None
        try:
            encoder.close()
        except (OSError, RuntimeError) as exc:
            self._partial.unlink(missing_ok=True)
            raise OutputError(f"{self.path}: the H.264 encoder failed to finish ({exc})") from None
        os.replace(self._partial, self.path)

    def _abort(self) -> None:
        """Stops the encoder and removes the partial file."""
        encoder, self._encoder = self._encoder, None
        if encoder is not None:
            with contextlib.suppress(OSError, RuntimeError):
                encoder.close()
        self._partial.unlink(missing_ok=True)

    def __enter__(self) -> VideoWriter:
        return self

    def __exit__(self, exc_type: object, *exc_info: object) -> None:
        if exc_type is None:
            self.close()
        else:
            self._abort()

    def __del__(self) -> None:
        if getattr(self, "_encoder", None) is not None:
            self._abort()

    def __repr__(self) -> str:
        state = "closed" if self.closed else f"{self.frames} frames"
        size = f"{self.width}x{self.height}"
        return f"VideoWriter({str(self.path)!r}, {self.fps:g} fps, {size}, {state})"


class SizedOnFirstFrame:
    """A :class:`VideoWriter` opened at the first frame written, whose size it takes.

    Nothing is written when no frame comes; :meth:`close` then does nothing.
    """

    def __init__(self, path: Path | str, fps: float) -> None:
        self.path, self.fps = Path(path), fps
        self._writer: VideoWriter | None = None

    def write(self, rgb: np.ndarray) -> None:
        """Appends one ``H×W×3`` RGB frame."""
        if self._writer is None:
            self._writer = VideoWriter(self.path, self.fps, (rgb.shape[1], rgb.shape[0]))
        self._writer.write(rgb)

    def close(self) -> None:
        """Finishes the file, if any frame was written."""
        if self._writer is not None:
            self._writer.close()


def probe(path: Path | str) -> dict:
    """What the bundled ffmpeg reads from a video: codec, pixel format, size, fps, frames.

    Decodes the whole file (small videos only: tests and checks).

    Raises:
        MissingDataError: No file at ``path``.
        HavlnError: ffmpeg cannot read it.
    """
    import imageio_ffmpeg

    from havln_mj.errors import MissingDataError

    path = Path(path)
    if not path.is_file():
        raise MissingDataError(f"no video at {path}")
    try:
        reader = imageio_ffmpeg.read_frames(str(path))
        meta = next(reader)
        frames = sum(1 for _ in reader)
    except (OSError, RuntimeError, StopIteration) as exc:
        raise OutputError(f"{path}: ffmpeg cannot read this video ({exc})") from None
    codec = str(meta.get("codec", "")).split()[0]
    return {
        "codec": codec,
        "pixel_format": str(meta.get("pix_fmt", "")).split("(")[0],
        "size": tuple(meta["size"]),
        "fps": float(meta["fps"]),
        "frames": frames,
        "duration_s": float(meta.get("duration", 0.0)),
    }
