"""Flower pigment pattern maps (Dong 2007 Ch. 3): venation (§3.3.1), venation-aware reaction-diffusion
(§3.3.2, Eqs. 3.1-3.5), pigment spectra, flower colour expression (§3.4, Eqs. 3.6-3.10) and YIQ
recolouring of a photograph (§3.5)."""
