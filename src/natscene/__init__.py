"""
natscene
========

natscene: render natural outdoor scenes from Dobashi 2012, Reimschuessel 2011 and Dong 2007.

The stages live in the subpackages (:mod:`natscene.volume`, :mod:`natscene.sky`, :mod:`natscene.scatter`,
:mod:`natscene.fit`, :mod:`natscene.keyframes`, :mod:`natscene.mie`, :mod:`natscene.patterns`,
:mod:`natscene.leaves`, :mod:`natscene.tiles`, :mod:`natscene.features`, :mod:`natscene.composite`,
:mod:`natscene.spectral`, :mod:`natscene.denoise`), the shared pieces in the top-level modules (colour, geometry,
phase function, I/O, config, memory, rule harness). The package itself offers :data:`__version__`.

Importing the package makes sure Dr.Jit will find a libLLVM it can load (see :mod:`natscene.llvm`)
before anything imports ``drjit`` or ``mitsuba``; nothing else happens at import time.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Dong, W. (2007). Rendering algorithms for natural scenes. PhD thesis, Université Henri Poincaré – Nancy 1.
-   Reimschuessel, C. A. (2011). Rendering realistic cloud effects for computer generated films. MSc thesis,
    Brigham Young University.
"""
from natscene import llvm as _llvm

__all__ = ["__version__"]

__version__ = "0.1.0"

_llvm.configure()
