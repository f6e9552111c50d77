"""Denoising of rendered frames (Monte Carlo noise of the forward renderer's path-traced terms).

``features``: the auxiliary feature images of the cloud that a learned denoiser is fed with, as production
renderers do (albedo and normal of what the pixel sees), computed from the volume and the frame's camera,
noise-free. ``oidn``: Intel Open Image Denoise through its Python binding ``pyoidn`` (the ``RT`` filter,
HDR, with the clean features). ``noise``: the noise figure of a frame (two renders with different seeds).
"""

__all__: list[str] = []  # a map of the package; import the module you need
