"""
Mitsuba variant
===============

Picks the Mitsuba 3 variant at run time (DESIGN §3): ``cuda_ad_*`` where a CUDA GPU works, else
``llvm_ad_*``; ``rgb`` or ``spectral`` as asked. The environment variable ``NATSCENE_MITSUBA_VARIANT``
forces one. Fails with a clear message when no variant can run:

-   :func:`select_variant`: activate and return the best working variant.
-   :class:`VariantError`: no variant could be activated.
"""
from __future__ import annotations

import os

import natscene.llvm  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit is imported)

__all__ = ["select_variant", "VariantError"]


class VariantError(RuntimeError):
    """No Mitsuba variant could be activated on this machine."""


def _try(mi, name: str) -> bool:
    if name not in mi.variants():
        return False
    try:
        mi.set_variant(name)
        import drjit as dr
        # Touch the backend: cuda variants import fine without a GPU and fail on first use.
        x = mi.Float([1.0, 2.0])
        dr.eval(x * 2)
        return True
    except Exception:  # noqa: BLE001 - any backend failure means "not this one"
        return False


def select_variant(spectral: bool = False, threads: int | None = None) -> str:
    """Activate and return the best working variant for ``spectral`` (False: rgb).

    ``threads`` pins Dr.Jit's thread pool (same seed + same thread count = identical bytes).
    """
    import mitsuba as mi

    kind = "spectral" if spectral else "rgb"
    forced = os.environ.get("NATSCENE_MITSUBA_VARIANT")
    order = [forced] if forced else [f"cuda_ad_{kind}", f"llvm_ad_{kind}"]
    for name in order:
        if _try(mi, name):
            if threads:
                import drjit as dr
                dr.set_thread_count(int(threads))
            return name
    raise VariantError(
        f"no Mitsuba variant works (tried {', '.join(order)}). On a CPU machine the llvm variants need a "
        f"libLLVM >= 16: run 'bash tools/setup.sh' or set DRJIT_LIBLLVM_PATH "
        f"(currently {os.environ.get('DRJIT_LIBLLVM_PATH')!r}).")
