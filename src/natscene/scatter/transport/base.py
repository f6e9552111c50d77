"""
Transport interface
===================

Defines the interface every transport model of the cloud implements (``precompute.transport``,
``shots.<name>.render``):

-   :class:`Transport`: the abstract model (precompute, save and load, composition, direct render, fit parameters).
-   :class:`Arrays`: the tables at N pixels, as the compositions read them.
-   :class:`RenderOptions`: the options of a direct render.
-   :func:`noise_stats`: median and 95th percentile of per-pixel noise figures.

A transport is the model of the light that scatters more than once inside the cloud (Dobashi 2012 Eqs. 6-8 and
their remedies): the rest of the cloud's image, single scattering by the ray-marched S_sun of Eq. 5, the sky seen
through the cloud (Eq. 9) and the atmosphere (Eq. 3), is common to all and lives in :mod:`natscene.scatter.single`,
:mod:`natscene.scatter.compose` and :mod:`natscene.scatter.render`. Each transport owns

- its part of the **precompute** (:meth:`Transport.precompute`: the tables' multiple-scattering fields and meta)
  and their file (:meth:`Transport.save`, :meth:`Transport.load`);
- its **composition** for the GA (:meth:`Transport.compose`: L_c of Eq. 4 for a population, from the tables);
- its **direct render** for the shots (:meth:`Transport.render`: the cloud's light at one parameter set);
- the **fit's parameters** (:attr:`Transport.fit_params`) and the settings it composes with every candidate
  (:meth:`Transport.fit_fixed`).

:mod:`natscene.scatter.transport` names the models; ``dobashi`` (:mod:`.dobashi`) and ``all_orders``
(:mod:`.all_orders`) implement them.

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

__all__ = ["Arrays", "RenderOptions", "Transport", "noise_stats"]


def noise_stats(values: list) -> dict | None:
    """Median and 95th percentile of the concatenated per-pixel figures (the meta's noise entries)."""
    v = np.concatenate(values) if values else np.zeros(0)
    return {"median": float(np.median(v)), "p95": float(np.percentile(v, 95))} if v.size else None


@dataclass
class Arrays:
    """The tables at N pixels, as the compositions read them: ``s_sun``, ``s_amb``, ``T`` (Ns, N); ``multiple``
    (Ng, Ns, K, N) (dobashi); ``sun_ms`` (Ng, Ns, B, N) and ``sky_ms`` (Ng, Ns, 4, B', N) (all_orders);
    ``cos_t`` (N,)."""

    s_sun: np.ndarray
    s_amb: np.ndarray
    T: np.ndarray
    multiple: np.ndarray | None
    sun_ms: np.ndarray | None
    sky_ms: np.ndarray | None
    cos_t: np.ndarray

    @property
    def n(self) -> int:
        return int(self.cos_t.size)


@dataclass
class RenderOptions:
    """The settings of a direct render that the transports read, built by :func:`natscene.scatter.render.render`
    from its settings (:func:`natscene.scatter.allorders.render_settings`: the schema's defaults are the only ones)
    and keywords: ``orders``, ``spp``, ``batch_spp`` (dobashi); ``all_orders`` (the transport's
    :class:`natscene.scatter.allorders.AllOrdersSettings`), ``sky_settings``, ``dome``, ``ground_albedo`` and
    ``skylight`` (all_orders)."""

    seed: int
    step_voxels: float
    supersample: int
    orders: int
    spp: int
    batch_spp: int | None
    sky_settings: object
    dome: object
    ground_albedo: object
    skylight: bool
    all_orders: object


class Transport(ABC):
    """One transport model (see the module docstring). Subclasses set ``name``, ``fit_params``,
    ``tables_file`` and implement the abstract methods."""

    name: str = ""
    fit_params: tuple = ()
    tables_file: str = ""

    def validate(self, settings) -> None:
        """Raise InputError naming the config key of a bad setting of this transport, before any work (none by
        default)."""

    @abstractmethod
    def describe(self, section: dict) -> str:
        """One line for the precompute's log: this transport's effort settings of a ``precompute`` section."""

    @abstractmethod
    def precompute(self, volume, med, camera, sigmas, gs, single, *, settings=None, skylight=None, n_m=4,
                   spp=256, seed=0, batch_spp=None, with_error=True, log=None) -> tuple[dict, dict]:
        """(the :class:`natscene.scatter.tables.Tables` fields of this transport, its meta) over the grid of unitless
        ``sigmas`` (extinction / extinction_scale) and ``gs``; ``single``: the grid's ray march."""

    @abstractmethod
    def save(self, directory, tables, attrs: dict) -> None:
        """Write :attr:`tables_file` of ``tables``."""

    @abstractmethod
    def load(self, directory, meta: dict, extinctions, gs, orders, shape) -> dict:
        """The Tables fields :meth:`save` wrote (read back from ``directory``)."""

    @abstractmethod
    def compose(self, tables, p: dict, P: int, arrays: Arrays, sky: np.ndarray, backend: str) -> np.ndarray:
        """L_c of Eq. 4 (P, N, 3) at the N pixels of ``arrays`` for the population ``p`` (``sky`` (N, 3))."""

    @abstractmethod
    def render(self, volume, med, camera, sigma: float, single: dict, cos_t, p: dict, sky,
               options: RenderOptions) -> tuple[np.ndarray, dict]:
        """(the cloud's light L_s + L_m (+ the skylight) (H, W, 3), components) at one parameter set ``p``."""

    @abstractmethod
    def preview_rows(self, tables, si: int, gis: list) -> list:
        """Rows of the precompute's contact sheet (:mod:`natscene.scatter.contact`): per row, a (name, image) per g
        node of ``gis``, at the extinction node ``si``."""

    @abstractmethod
    def values_per_node(self, section: dict) -> int:
        """Table images per (g, extinction) node for a ``precompute`` section (the memory model's table size)."""

    def memory_model(self, rule: str) -> str:
        """The key of :data:`natscene.resources.MODEL` that models ``rule``'s memory with this transport."""
        return rule

    def fit_fixed(self, tables, sky, settings, log) -> dict:
        """Settings composed with every GA candidate (the fit's ``fixed``); none by default."""
        return {}
