"""Keyframe interpolation and animated shots (Dobashi et al. 2012 §5.2, §6; Figs. 13 and 15).

``interpolate``: linear blends of parameters and colours, slerp of sun directions, linear or Catmull-Rom
camera paths, easing. ``shot``: a shot's keyframes resolved from the config and the fits, the keyframes a
frame depends on, the per-frame parameter set. ``sky``: the analytic (Preetham 1999) sky behind the clouds.
``animation``: mp4 / gif and filmstrip from the frames. ``frame``: one frame of a shot (the forward renderer, the
denoiser and the ``mie_blend`` shading).
"""

__all__: list[str] = []  # a map of the package; import the module you need
