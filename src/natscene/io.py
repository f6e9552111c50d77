"""
Image and file I/O
==================

Defines the image and file I/O of the project, the only module that touches OpenImageIO (DESIGN §2-3):

-   :func:`read_exr`, :func:`write_exr`: OpenEXR images (an :class:`Image`) with named channels and attributes.
-   :func:`read_photo`, :func:`read_mask`, :func:`read_image_u8`, :func:`check_complete`: photographs, masks and
    8-bit images, damaged files refused.
-   :func:`write_png`, :func:`to_srgb8`, :func:`auto_exposure`: the PNG previews and their tone map.
-   :func:`read_yaml`, :func:`write_yaml`, :func:`write_text`: YAML and text files.
-   :func:`atomic_path`, :func:`remove_stale_temps`: atomic writes and the temporary files of a killed job.
-   :func:`texture_lookup_reference`: filtered texture lookups through OpenImageIO (a test reference).

- EXR read/write with any number of named channels, float32 or half, header attributes recording the
  stage, its parameters and the library version;
- every writer is atomic: it writes a temporary file beside the target and renames it, so an
  interrupted or failing job never leaves a half-written file that Snakemake would take as done; the
  temporary files a killed job left behind are removed by the next run of that job
  (:func:`remove_stale_temps`, called by :mod:`natscene.runner` for every output);
- outputs are byte-identical across reruns: no wall-clock time in any header (OpenImageIO's EXR writer
  would add a ``DateTime``/``capDate`` attribute; :func:`write_exr` suppresses it);
- a photo or texture that its decoder reports as damaged (a truncated JPEG, which libjpeg would otherwise
  fill with grey, a PNG cut short) is refused with the file's name (:func:`check_complete`);
- photographs (JPEG, PNG 8/16-bit, EXR) are read to linear float32 (sRGB decoding by colour-science);
- PNG previews: linear -> exposure -> clip -> sRGB encoding, 8 bit. The default exposure maps the
  99.5th percentile of luminance to 1 ("auto"), documented in the README.
"""
from __future__ import annotations

import contextlib
import json
import os
import re
import tempfile
from pathlib import Path
from typing import Iterator, Mapping, NamedTuple, Sequence

import numpy as np
import OpenImageIO as oiio
import yaml

from natscene import __version__
from natscene.color import linear_to_srgb, luminance, srgb_to_linear
from natscene.errors import InputError

# InputError is natscene.errors'; it is listed because scripts/fit.py and scripts/render_frame.py raise
# ``io.InputError``.
__all__ = ["read_exr", "write_exr", "Image", "read_photo", "read_mask", "read_image_u8", "check_complete",
           "write_png", "to_srgb8", "auto_exposure", "read_yaml", "write_yaml", "write_text", "atomic_path",
           "remove_stale_temps", "texture_lookup_reference", "InputError"]

ATTR_PREFIX = "natscene:"

# OpenImageIO refuses to read an image of more than 1024 channels by default (a guard against corrupt headers);
# the all-orders tables hold (sun bands + 4 x sky bands) x g x extinction channels: 23 x 5 x 9 = 1035 in the
# main job
oiio.attribute("limits:channels", 1 << 16)


class Image(NamedTuple):
    """An image read from disk: pixels (H, W, C) float32, channel names, header attributes."""

    pixels: np.ndarray
    channels: list[str]
    attrs: dict

    def channel(self, *names: str) -> np.ndarray:
        """The named channels stacked on the last axis (one name: a 2-D array)."""
        missing = [n for n in names if n not in self.channels]
        if missing:
            raise KeyError(f"channels {missing} not in image (has {self.channels[:12]}...)")
        idx = [self.channels.index(n) for n in names]
        return self.pixels[..., idx[0]] if len(idx) == 1 else self.pixels[..., idx]


# ----------------------------------------------------------------------------------------- atomic
def _temp_prefix(path: Path) -> str:
    return f".{path.stem}."


def remove_stale_temps(path: str | os.PathLike) -> list[Path]:
    """Remove the temporary files :func:`atomic_path` left beside ``path`` in an earlier, killed run.

    Only names of the exact form ``.{stem}.XXXXXXXX{suffix}`` (``tempfile.mkstemp``'s 8 random
    characters) are removed. Snakemake runs one job per output at a time, so no live writer owns them.
    Returns the removed paths.
    """
    path = Path(path)
    if not path.parent.is_dir():
        return []
    pattern = re.compile(re.escape(_temp_prefix(path)) + r"[a-z0-9_]{8}" + re.escape(path.suffix or ".tmp") + "$")
    removed = []
    for f in path.parent.iterdir():
        if pattern.match(f.name) and f.is_file():
            with contextlib.suppress(FileNotFoundError):
                f.unlink()
                removed.append(f)
    return removed


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` (same extension); rename it onto ``path`` on success.

    On any exception the temporary file is removed and ``path`` is left untouched.
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(f"cannot create output directory {path.parent}: {e.strerror}. "
                         f"Choose a writable results directory.") from e
    if not os.access(path.parent, os.W_OK):
        raise InputError(f"output directory {path.parent} is not writable; fix its permissions or run "
                         f"the workflow in a writable directory (snakemake --directory).")
    fd, tmp = tempfile.mkstemp(prefix=_temp_prefix(path), suffix=path.suffix or ".tmp", dir=path.parent)
    os.close(fd)
    tmp = Path(tmp)
    try:
        yield tmp
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; give the file the usual permissions
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        raise


def write_text(path: str | os.PathLike, text: str) -> None:
    """Write a text file atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def write_yaml(path: str | os.PathLike, data) -> None:
    """Write YAML atomically (plain Python types; numpy scalars/arrays are converted)."""
    write_text(path, yaml.safe_dump(to_builtin(data), sort_keys=False))


def read_yaml(path: str | os.PathLike):
    """Read a YAML file, with a clear error when it is missing or malformed."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: file not found")
    try:
        return yaml.safe_load(path.read_text())
    except yaml.YAMLError as e:
        raise InputError(f"{path}: not valid YAML ({e})") from e


def to_builtin(obj):
    """Convert numpy scalars/arrays (recursively) to plain Python for YAML/JSON."""
    if isinstance(obj, Mapping):
        return {str(k): to_builtin(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_builtin(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_builtin(obj.tolist())
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    return obj


# ------------------------------------------------------------------------------------------- EXR
def _as_hwc(pixels: np.ndarray) -> np.ndarray:
    a = np.asarray(pixels)
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3:
        raise ValueError(f"image must be (H, W) or (H, W, C), got shape {a.shape}")
    return a


def default_channel_names(n: int) -> list[str]:
    """R,G,B,A-style names for 1-4 channels, else c0..c{n-1}."""
    return {1: ["Y"], 2: ["Y", "A"], 3: ["R", "G", "B"], 4: ["R", "G", "B", "A"]}.get(n, [f"c{i}" for i in range(n)])


def write_exr(path: str | os.PathLike, pixels: np.ndarray, channels: Sequence[str] | None = None,
              attrs: Mapping | None = None, half: bool = False, stage: str | None = None) -> None:
    """Write an OpenEXR image atomically.

    ``pixels``: (H, W) or (H, W, C); ``channels``: C names (default R,G,B[,A]); ``attrs``: header
    attributes (str/int stored natively, floats and anything else as JSON so doubles round-trip), stored with the prefix
    ``natscene:``; ``half`` stores 16-bit floats (use only where the error stays below 1e-3 relative).
    """
    a = _as_hwc(pixels)
    h, w, c = a.shape
    names = list(channels) if channels is not None else default_channel_names(c)
    if len(names) != c:
        raise ValueError(f"{path}: {c} channels but {len(names)} channel names")
    if len(set(names)) != len(names):
        raise ValueError(f"{path}: duplicate channel names")
    spec = oiio.ImageSpec(w, h, c, oiio.HALF if half else oiio.FLOAT)
    spec.channelnames = tuple(names)
    spec.attribute("compression", "zip")
    spec.attribute("DateTime", "")  # an empty value keeps OpenImageIO from stamping the wall-clock time
    spec.attribute(ATTR_PREFIX + "version", __version__)
    # OpenEXR stores channels sorted by name; remember the order they were given in.
    spec.attribute(ATTR_PREFIX + "channel_order", ",".join(names))
    if stage:
        spec.attribute(ATTR_PREFIX + "stage", stage)
    for key, value in (attrs or {}).items():
        key = ATTR_PREFIX + str(key)
        value = to_builtin(value)
        # floats go through JSON too: an EXR float attribute is 32-bit and would not round-trip a double
        if isinstance(value, (bool, float)) or not isinstance(value, (str, int)):
            spec.attribute(key, "json:" + json.dumps(value))
        elif isinstance(value, int) and not (-2**31 <= value < 2**31):
            spec.attribute(key, "json:" + json.dumps(value))
        else:
            spec.attribute(key, value)
    data = np.ascontiguousarray(a, dtype=np.float16 if half else np.float32)
    with atomic_path(path) as tmp:
        out = oiio.ImageOutput.create(str(tmp))
        if out is None or not out.open(str(tmp), spec):
            raise OSError(f"cannot open {path} for writing: {oiio.geterror()}")
        try:
            if not out.write_image(data):
                raise OSError(f"cannot write {path}: {out.geterror()}")
        finally:
            out.close()


def _attr_value(v):
    if isinstance(v, str) and v.startswith("json:"):
        return json.loads(v[5:])
    return v


def check_complete(path: str | os.PathLike, data: bytes | None = None) -> None:
    """Refuse a JPEG or PNG whose byte stream is cut short (InputError naming the file).

    JPEG: the end-of-image marker (FF D9) must follow the first start-of-scan of the *main* image (marker
    segments are walked by their lengths, so an EXIF thumbnail's own markers do not count; inside
    entropy-coded data FF is always stuffed, so FF D9 there is the real end). PNG: the IEND chunk must be
    present. Other formats rely on their decoder's error state (see :func:`_read_pixels`).
    """
    path = Path(path)
    if data is None:
        with open(path, "rb") as f:
            data = f.read()
    if data[:2] == b"\xff\xd8":  # JPEG
        i, n = 2, len(data)
        while i + 4 <= n:
            if data[i] != 0xFF:
                break  # not a marker where one must be: let the decoder judge
            marker = data[i + 1]
            if marker == 0xFF:  # fill byte
                i += 1
                continue
            if marker in (0xD8, 0x01) or 0xD0 <= marker <= 0xD7:
                i += 2
                continue
            if marker == 0xD9:
                raise InputError(f"{path}: JPEG ends before its image data; the file is damaged. Re-export it")
            seg = int.from_bytes(data[i + 2:i + 4], "big")
            if marker == 0xDA:  # start of scan: the main image's data follows
                if data.find(b"\xff\xd9", i + 2 + seg) < 0:
                    raise InputError(f"{path}: truncated JPEG ({n} bytes, no end-of-image marker): the decoder "
                                     f"would fill the missing part with grey. Copy or download the file again")
                return
            i += 2 + seg
        raise InputError(f"{path}: truncated JPEG ({n} bytes, no image data): copy or download the file again")
    if data[:8] == b"\x89PNG\r\n\x1a\n" and b"IEND" not in data[-64:]:
        raise InputError(f"{path}: truncated PNG ({len(data)} bytes, no IEND chunk): copy or export the file again")


def _decoder_error(inp) -> str:
    """The decoder's error message, '' if none (``has_error`` is a property in OIIO 3.x, a method before)."""
    has = getattr(inp, "has_error", None)
    has = has() if callable(has) else has
    msg = inp.geterror() if (has is None or has) else ""
    return (msg or "").strip()


def _read_pixels(path: Path, what: str, fmt=oiio.FLOAT):
    """Open any OIIO-readable image; return (pixels (H, W, C) in ``fmt``, spec), or raise InputError.

    A decoder error or warning (e.g. libjpeg's "Premature end of JPEG file", after which it fills the rest
    of the image with grey) is an error naming the file, as is a truncated byte stream (:func:`check_complete`).
    """
    if not path.is_file():
        raise InputError(f"{path}: {what} not found")
    with open(path, "rb") as f:
        head = f.read(8)
    if head[:2] == b"\xff\xd8" or head == b"\x89PNG\r\n\x1a\n":  # JPEG or PNG, whatever the name says
        check_complete(path)
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise InputError(f"{path}: not a readable image ({oiio.geterror().strip() or 'unknown format'})")
    try:
        spec = inp.spec()
        pixels = inp.read_image(0, 0, 0, spec.nchannels, fmt)
        err = _decoder_error(inp)
        if pixels is None or err:
            raise InputError(f"{path}: cannot decode the {what}: {err or 'unknown decoder error'}. The file is "
                             f"damaged or truncated; copy or export it again")
    finally:
        inp.close()
    dtype = np.uint8 if fmt == oiio.UINT8 else np.float32
    return np.asarray(pixels, dtype).reshape(spec.height, spec.width, spec.nchannels), spec


def read_exr(path: str | os.PathLike) -> Image:
    """Read an OpenEXR (or any OIIO-readable) image as float32 (H, W, C) with names and attributes.

    Attributes written by :func:`write_exr` come back without their ``natscene:`` prefix.
    """
    pixels, spec = _read_pixels(Path(path), "image")
    attrs = {}
    for p in spec.extra_attribs:
        name = p.name[len(ATTR_PREFIX):] if p.name.startswith(ATTR_PREFIX) else p.name
        attrs[name] = _attr_value(p.value)
    names = list(spec.channelnames)
    order = attrs.pop("channel_order", None)
    if order:
        wanted = order.split(",")
        if sorted(wanted) == sorted(names):
            pixels = pixels[..., [names.index(n) for n in wanted]]
            names = wanted
    return Image(np.ascontiguousarray(pixels), names, attrs)


# ----------------------------------------------------------------------------------------- photos
def read_photo(path: str | os.PathLike, keep_alpha: bool = False) -> np.ndarray:
    """Read a photograph to linear float32 (H, W, C).

    8/16-bit JPEG/PNG/TIFF are sRGB-decoded with colour-science; float formats (EXR, HDR) are taken as
    linear. Alpha is dropped unless ``keep_alpha``. Greyscale images come back with C = 1.
    """
    path = Path(path)
    a, spec = _read_pixels(path, "photo")
    is_float = spec.format.basetype in (oiio.FLOAT, oiio.HALF, oiio.DOUBLE)
    alpha_idx = spec.alpha_channel
    alpha = None
    if alpha_idx >= 0:
        alpha = a[..., alpha_idx:alpha_idx + 1]
        a = np.delete(a, alpha_idx, axis=-1)
    if a.shape[-1] == 2:  # luminance + something: keep luminance
        a = a[..., :1]
    a = a[..., :3]
    if not is_float:
        a = srgb_to_linear(a)
    if keep_alpha and alpha is not None:
        a = np.concatenate([a, alpha], axis=-1)
    return np.ascontiguousarray(a, np.float32)


def read_mask(path: str | os.PathLike) -> np.ndarray:
    """Read a mask image as float32 (H, W) in [0, 1] without any colour decoding (first channel)."""
    a, _ = _read_pixels(Path(path), "mask")
    return a[..., 0].copy()


# ------------------------------------------------------------------------------------------- PNG
def auto_exposure(linear: np.ndarray, percentile: float = 99.5) -> float:
    """Exposure that maps the given percentile of luminance (of finite, positive pixels) to 1."""
    a = _as_hwc(linear)
    y = luminance(a) if a.shape[-1] >= 3 else a[..., 0]
    y = y[np.isfinite(y) & (y > 0)]
    if y.size == 0:
        return 1.0
    p = float(np.percentile(y, percentile))
    return 1.0 / p if p > 0 else 1.0


def to_srgb8(linear: np.ndarray, exposure: float | str | None = "auto") -> np.ndarray:
    """The documented preview tone map: ``sRGB_encode(clip(exposure * linear, 0, 1))`` as uint8.

    ``exposure="auto"`` uses :func:`auto_exposure`; ``None`` or 1 means no scaling.
    """
    a = _as_hwc(linear).astype(np.float32)
    if a.shape[-1] == 1:
        a = np.repeat(a, 3, axis=-1)
    if a.shape[-1] == 2:
        a = np.concatenate([a[..., :1]] * 3, axis=-1)
    rgb = a[..., :3]
    k = auto_exposure(rgb) if exposure == "auto" else (1.0 if exposure is None else float(exposure))
    rgb = np.nan_to_num(rgb * k, nan=0.0, posinf=1.0, neginf=0.0)
    return np.round(linear_to_srgb(rgb) * 255.0).astype(np.uint8)


def write_png(path: str | os.PathLike, image: np.ndarray, exposure: float | str | None = "auto",
              encoded: bool = False) -> None:
    """Write an 8-bit sRGB PNG preview atomically.

    ``image`` is linear (tone-mapped by :func:`to_srgb8`) unless ``encoded`` is True, in which case it
    is already display-encoded: uint8, or float in [0, 1].
    """
    if encoded:
        a = _as_hwc(image)
        data = a if a.dtype == np.uint8 else np.round(np.clip(a, 0, 1) * 255).astype(np.uint8)
    else:
        data = to_srgb8(image, exposure)
    h, w, c = data.shape
    spec = oiio.ImageSpec(w, h, c, oiio.UINT8)
    with atomic_path(path) as tmp:
        out = oiio.ImageOutput.create(str(tmp))
        if out is None or not out.open(str(tmp), spec):
            raise OSError(f"cannot open {path} for writing: {oiio.geterror()}")
        try:
            if not out.write_image(np.ascontiguousarray(data)):
                raise OSError(f"cannot write {path}: {out.geterror()}")
        finally:
            out.close()


def read_image_u8(path: str | os.PathLike) -> np.ndarray:
    """Read an 8-bit image (PNG/JPEG) as stored, uint8 (H, W, C), no colour decoding."""
    return _read_pixels(Path(path), "image", oiio.UINT8)[0]


# ---------------------------------------------------------------------------------------- textures
def texture_lookup_reference(pixels: np.ndarray, uv: np.ndarray, duv_dx: np.ndarray, duv_dy: np.ndarray,
                             wrap: bool = True, max_aniso: int = 16) -> np.ndarray:
    """Filtered lookups of an image through OpenImageIO's ``TextureSystem`` (a mip-mapped texture made with
    ``make_texture``, anisotropic filtering, bilinear texel interpolation, periodic or clamped wrap): (M, C) for (u, v) points with v up and
    their footprint derivatives (M, 2). OIIO's Python binding takes one point per call, so this is a reference
    for tests and spot checks, not for rendering (natscene.composite.texture filters whole frames)."""
    a = _as_hwc(np.asarray(pixels, np.float32))
    with tempfile.TemporaryDirectory() as d:
        src, tx = os.path.join(d, "src.exr"), os.path.join(d, "tex.tx")
        spec = oiio.ImageSpec(a.shape[1], a.shape[0], a.shape[2], oiio.FLOAT)
        buf = oiio.ImageBuf(spec)
        buf.set_pixels(oiio.ROI(), np.ascontiguousarray(a))
        if not buf.write(src):
            raise OSError(f"cannot write {src}: {buf.geterror()}")
        if not oiio.ImageBufAlgo.make_texture(oiio.MakeTxTexture, src, tx, oiio.ImageSpec()):
            raise OSError(f"make_texture failed: {oiio.geterror()}")
        ts = oiio.TextureSystem(False)
        opt = oiio.TextureOpt()
        w = oiio.Wrap.Periodic if wrap else oiio.Wrap.Clamp
        opt.swrap, opt.twrap = w, w
        opt.mipmode = oiio.MipMode.Aniso
        opt.interpmode = oiio.InterpMode.Bilinear
        opt.anisotropic = int(max_aniso)
        uv, dx, dy = (np.asarray(x, np.float64).reshape(-1, 2) for x in (uv, duv_dx, duv_dy))
        out = np.array([ts.texture(tx, opt, float(p[0]), float(1.0 - p[1]), float(ddx[0]), float(-ddx[1]),
                                   float(ddy[0]), float(-ddy[1]), a.shape[2]) for p, ddx, ddy in zip(uv, dx, dy)],
                       np.float32)
        ts.close_all()
        return out.reshape(-1, a.shape[2])
