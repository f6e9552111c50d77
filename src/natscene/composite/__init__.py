"""Final compositing of a shot (Dong 2007 Ch. 2): hybrid RGB + spectral intermediate image, the Mitsuba
scene of the set (ground, leaves/petals, thin-film objects) and the full-spectral reference mode."""
