"""
Complex refractive indices
==========================

Defines the measured complex refractive indices n̂ = n + iκ of metals (Dong 2007, §1.1.6, §2.5: gold film on
copper, indices from measured data [Pal85]):

-   :func:`complex_index`: n + iκ of a named metal at given wavelengths.
-   :func:`ior_directory`: Mitsuba's directory of spectral index tables.

The data are the spectral conductor tables that ship with Mitsuba 3 (``mitsuba/data/ior/<name>.eta.spd`` and
``<name>.k.spd``, the files Mitsuba's ``conductor`` plugin loads in its spectral variants). Their headers
say "data from www.luxpop.com database" (LuxPop optical constants, compiled from the handbook literature;
the ``*_palik`` files are Palik's Handbook of Optical Constants of Solids, 1985, Dong's [Pal85]). Each row is
``wavelength_nm value``. Au and Cu default to the plain tables (298-886 nm, cover the visible range);
``Cu_palik`` is available too. Linear interpolation onto the wavelength grid.

References
----------
-   Dong, W. (2007). Rendering algorithms for natural scenes. PhD thesis, Université Henri Poincaré – Nancy 1.
-   Jakob, W., et al. (2022). Mitsuba 3 renderer. https://mitsuba-renderer.org
-   Palik, E. D. (1985). Handbook of Optical Constants of Solids. Academic Press.
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from natscene.errors import InputError

__all__ = ["complex_index", "ior_directory"]


def ior_directory() -> Path:
    """Mitsuba's directory of spectral index tables."""
    import mitsuba  # noqa: F401  (only to locate the package; no variant needed)
    return Path(mitsuba.__file__).resolve().parent / "data" / "ior"


def _read_spd(path: Path) -> tuple[np.ndarray, np.ndarray]:
    rows = []
    for line in path.read_text().splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        parts = line.split()
        rows.append((float(parts[0]), float(parts[1])))
    a = np.array(rows, np.float64)
    order = np.argsort(a[:, 0])
    return a[order, 0], a[order, 1]


@lru_cache(maxsize=32)
def _table(name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    d = ior_directory()
    fe, fk = d / f"{name}.eta.spd", d / f"{name}.k.spd"
    if not fe.is_file() or not fk.is_file():
        have = sorted({p.name.split(".")[0] for p in d.glob("*.eta.spd")})
        raise InputError(f"no measured index data for material {name!r} in {d}; available: {', '.join(have)}")
    we, n = _read_spd(fe)
    wk, k = _read_spd(fk)
    if not np.array_equal(we, wk):
        k = np.interp(we, wk, k)
    return we, n, k


def complex_index(material, wavelengths_nm) -> np.ndarray:
    """n + iκ at the wavelengths (nm).

    ``material``: a name of a Mitsuba table (``"Au"``, ``"Cu"``, ``"Cu_palik"``, ...), ``"air"``/``"vacuum"``
    (1.0), a real number (non-absorbing dielectric), a complex number, or a string holding one in Python
    notation (``"2.0+0.05j"``: n = 2.0, κ = 0.05; constant over wavelength).
    """
    wl = np.asarray(wavelengths_nm, np.float64)
    if isinstance(material, (int, float, complex, np.number)):
        return np.full(wl.shape, complex(material), np.complex128)
    name = str(material).strip()
    if name.lower() in ("air", "vacuum"):
        return np.ones(wl.shape, np.complex128)
    try:
        value = complex(name.replace(" ", ""))
    except ValueError:
        value = None
    if value is not None:
        if value.real <= 0 or value.imag < 0:
            raise InputError(f"index {name!r}: need n > 0 and kappa >= 0 (n + kappa j)")
        return np.full(wl.shape, value, np.complex128)
    w, n, k = _table(name)
    if wl.min() < w[0] - 1e-6 or wl.max() > w[-1] + 1e-6:
        raise InputError(f"index table {name!r} covers {w[0]:.0f}-{w[-1]:.0f} nm, asked {wl.min():.0f}-{wl.max():.0f} nm")
    return np.interp(wl, w, n) + 1j * np.interp(wl, w, k)
