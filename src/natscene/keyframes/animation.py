"""
Animation and filmstrip of a shot
=================================

Defines the shot's frames as an animation and a filmstrip (Dobashi et al. 2012, Figs. 13, 15: snapshots of an
animation):

-   :func:`write_animation`: the frames as mp4 or gif; :func:`ffmpeg_available`, :func:`animation_suffix`: which.
-   :func:`filmstrip`: frames side by side; :func:`strip_indices`: which frames; :func:`downscale`: to a height.

``write_animation``: an H.264 mp4 through imageio-ffmpeg (it ships its own ffmpeg binary; yuv420p, so
frame sizes are padded to even numbers) or, where no encoder is available or the name ends in ``.gif``, an
animated GIF (imageio/Pillow, looping). ``filmstrip``: n frames evenly spread over the shot (first and last
included) side by side, downscaled to a common height (area averaging), with thin gaps.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from natscene.io import atomic_path

__all__ = ["ffmpeg_available", "animation_suffix", "write_animation", "downscale", "strip_indices", "filmstrip"]


def ffmpeg_available() -> bool:
    """True when imageio-ffmpeg can find an ffmpeg executable."""
    try:
        import imageio_ffmpeg

        return bool(imageio_ffmpeg.get_ffmpeg_exe())
    except Exception:  # noqa: BLE001 - any failure means: no encoder
        return False


def animation_suffix() -> str:
    """``.mp4`` where an encoder is available, else ``.gif``."""
    return ".mp4" if ffmpeg_available() else ".gif"


def _even(frame: np.ndarray) -> np.ndarray:
    h, w = frame.shape[:2]
    return np.pad(frame, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")


def write_animation(path, frames: list, fps: float = 12.0) -> None:
    """Write uint8 RGB frames (H, W, 3) as mp4 or gif (by ``path``'s suffix), atomically."""
    import imageio.v3 as iio

    path = Path(path)
    if not frames:
        raise ValueError("write_animation: no frames")
    frames = [np.ascontiguousarray(f[..., :3]) for f in frames]
    with atomic_path(path) as tmp:
        if path.suffix.lower() == ".mp4":
            import imageio_ffmpeg

            h, w = _even(frames[0]).shape[:2]
            writer = imageio_ffmpeg.write_frames(str(tmp), (w, h), fps=fps, codec="libx264", pix_fmt_out="yuv420p",
                                                 quality=8, macro_block_size=1, ffmpeg_log_level="error")
            writer.send(None)
            try:
                for f in frames:
                    writer.send(np.ascontiguousarray(_even(f)))
            finally:
                writer.close()
        else:
            iio.imwrite(tmp, np.stack(frames), extension=".gif", duration=1000.0 / fps, loop=0)


def downscale(img: np.ndarray, height: int) -> np.ndarray:
    """Area-average an (H, W, C) image to the given height (aspect kept); integer factors exactly."""
    import cv2

    h, w = img.shape[:2]
    if height >= h:
        return img
    width = max(1, round(w * height / h))
    return cv2.resize(img, (width, height), interpolation=cv2.INTER_AREA)


def strip_indices(n_frames: int, count: int) -> list[int]:
    """``count`` frame indices evenly spread over [0, n_frames - 1], first and last included."""
    count = max(1, min(count, n_frames))
    if count == 1:
        return [0]
    return sorted({int(round(i * (n_frames - 1) / (count - 1))) for i in range(count)})


def filmstrip(frames: list, height: int = 120, gap: int = 4, background: int = 255) -> np.ndarray:
    """Frames (uint8 (H, W, 3)) side by side at the given height, separated by ``gap`` pixels."""
    tiles = [downscale(f[..., :3], height) for f in frames]
    h = max(t.shape[0] for t in tiles)
    width = sum(t.shape[1] for t in tiles) + gap * (len(tiles) - 1)
    out = np.full((h, width, 3), background, np.uint8)
    x = 0
    for t in tiles:
        out[:t.shape[0], x:x + t.shape[1]] = t
        x += t.shape[1] + gap
    return out
