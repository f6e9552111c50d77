"""Spectral colour (Dong 2007 Ch. 2 and §1.1.6): wavelength grid and CIE integration, RGB -> spectrum
upsampling, illuminant SPDs, measured metal indices and multilayer thin-film reflectance."""
