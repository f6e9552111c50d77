"""
Intel Open Image Denoise
========================

Defines the denoiser of the frames, Intel Open Image Denoise (OIDN 2.x) through its Python binding ``pyoidn``: the
``RT`` filter on an HDR frame with clean albedo and normal features (:mod:`natscene.denoise.features`):

-   :func:`denoise_frame`: the denoised frame, changed only where the cloud covers it.
-   :class:`OIDN`: a committed OIDN CPU device and ``RT`` filter (:data:`QUALITIES`).
-   :class:`DenoiserUnavailable`: raised when the denoiser cannot be loaded on this machine.

OIDN is a convolutional network trained on path-traced images; fed with noise-free auxiliary images of what
each pixel sees it keeps the edges and texture those images show and removes the Monte Carlo noise of the
colour. Settings used here (OIDN's documentation, "RT" filter): ``hdr`` on (linear scene-referred radiance;
``inputScale`` left to OIDN's automatic exposure estimate), ``cleanAux`` on (the features are exact), the quality
of ``shots.<name>.denoiser.quality`` (``high`` for final frames; ``balanced``/``fast`` trade quality for speed),
the CPU device with ``numThreads`` = the job's threads (so a frame job keeps to the cores Snakemake gave it).

The denoiser only changes what the cloud covers: ``out = raw + coverage (oidn(raw) - raw)``, coverage the
fraction of a pixel's sub-rays that meet the cloud. Elsewhere the frame is the analytic sky, which carries no
noise, and stays exactly as rendered.

References
----------
-   Intel Open Image Denoise (OIDN) 2.x documentation, "RT" filter. https://www.openimagedenoise.org/documentation.html
"""
from __future__ import annotations

import numpy as np

from natscene.errors import InputError

__all__ = ["QUALITIES", "DenoiserUnavailable", "OIDN", "denoise_frame"]

QUALITIES = ("high", "balanced", "fast")


class DenoiserUnavailable(InputError):
    """The denoiser was asked for (config key) but cannot be loaded on this machine."""


class OIDN:
    """A committed OIDN CPU device and ``RT`` filter; call it on (color, albedo, normal) float32 (H, W, 3).
    ``quality``: one of :data:`QUALITIES` (None: the schema's ``shots.<name>.denoiser.quality``)."""

    def __init__(self, key: str = "denoise", threads: int | None = None, quality: str | None = None):
        if quality is None:
            from natscene.denoise.features import denoiser_settings
            quality = denoiser_settings()["quality"]
        if quality not in QUALITIES:
            raise InputError(f"config key '{key}': denoiser quality {quality!r} is not one of {QUALITIES}")
        try:
            import pyoidn

            dev = pyoidn.Device(pyoidn.OIDN_DEVICE_TYPE_CPU)
            if threads:
                dev.set_int("numThreads", int(threads))
            dev.commit()
            err = dev.get_error()
            if err:
                raise RuntimeError(err)
        except Exception as e:  # noqa: BLE001 - any failure to load is reported the same way
            raise DenoiserUnavailable(
                f"config key '{key}' is 'oidn', but Intel Open Image Denoise cannot be loaded "
                f"({type(e).__name__}: {e}); run `make setup` (it installs the Python package pyoidn) or set "
                f"'{key}: none' to write the frames without denoising") from e
        self._pyoidn = pyoidn
        self.device = dev
        self.key = key
        self.quality = {"high": pyoidn.OIDN_QUALITY_HIGH, "balanced": pyoidn.OIDN_QUALITY_BALANCED,
                        "fast": pyoidn.OIDN_QUALITY_FAST}[quality]

    def __call__(self, color: np.ndarray, albedo: np.ndarray | None = None,
                 normal: np.ndarray | None = None) -> np.ndarray:
        po = self._pyoidn
        c = np.ascontiguousarray(np.nan_to_num(np.clip(color, 0.0, None)), np.float32)
        if c.ndim != 3 or c.shape[-1] != 3:
            raise ValueError(f"denoise: colour must be (H, W, 3), got {c.shape}")
        out = np.zeros_like(c)
        keep = [c, out]
        flt = po.Filter(self.device, po.OIDN_FILTER_TYPE_RT)
        try:
            flt.set_image(po.OIDN_IMAGE_COLOR, c, po.OIDN_FORMAT_FLOAT3)
            flt.set_image(po.OIDN_IMAGE_OUTPUT, out, po.OIDN_FORMAT_FLOAT3)
            for name, img in ((po.OIDN_IMAGE_ALBEDO, albedo), (po.OIDN_IMAGE_NORMAL, normal)):
                if img is not None:
                    a = np.ascontiguousarray(img, np.float32)
                    if a.shape != c.shape:
                        raise ValueError(f"denoise: {name} has shape {a.shape}, colour {c.shape}")
                    keep.append(a)
                    flt.set_image(name, a, po.OIDN_FORMAT_FLOAT3)
            flt.set_bool("hdr", True)
            flt.set_bool("cleanAux", albedo is not None)
            flt.set_quality(self.quality)
            flt.commit()
            flt.execute()
            err = self.device.get_error()
            if err:
                raise RuntimeError(f"OIDN failed: {err}")
        finally:
            flt.release()
        del keep
        return out

    def close(self) -> None:
        self.device.release()


def denoise_frame(color: np.ndarray, features: dict, denoiser) -> np.ndarray:
    """The denoised frame: ``color + coverage (denoiser(color, albedo, normal) - color)`` (float32 (H, W, 3))."""
    d = denoiser(color, features["albedo"], features["normal"])
    cov = np.clip(np.asarray(features["coverage"], np.float32), 0.0, 1.0)[..., None]
    return np.clip(color + cov * (d - color), 0.0, None).astype(np.float32)
