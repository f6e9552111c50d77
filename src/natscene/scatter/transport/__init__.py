"""The transport models of the cloud's multiple scattering (``precompute.transport``, ``shots.<name>.render.transport``).

Each model owns its precompute, its composition for the GA and its direct render behind one interface
(:class:`natscene.scatter.transport.base.Transport`), which the precompute (:mod:`natscene.scatter.tables`), the
fit (:mod:`natscene.fit`) and the shots (:mod:`natscene.scatter.render`) call:

- ``all_orders`` (default, :mod:`.all_orders`): every order of the sun's light and the skylight, in bands of
  orders whose albedo dependence is closed-form (Dobashi 2012 §7's remedies);
- ``dobashi`` (:mod:`.dobashi`): the paper's orders 2..n_m by path tracing plus the ambient term (§4.3).
"""
from __future__ import annotations

from natscene.errors import InputError
from natscene.scatter.transport.base import Transport

__all__ = ["TRANSPORTS", "Transport", "get", "of"]

TRANSPORTS = ("all_orders", "dobashi")


def get(name: str, key: str = "precompute.transport") -> Transport:
    """The transport model called ``name``; an unknown name raises InputError naming the config ``key``."""
    if name == "all_orders":
        from natscene.scatter.transport.all_orders import AllOrders
        return AllOrders()
    if name == "dobashi":
        from natscene.scatter.transport.dobashi import Dobashi
        return Dobashi()
    raise InputError(f"config key '{key}': unknown transport {name!r} (one of {', '.join(TRANSPORTS)})")


def of(tables) -> Transport:
    """The transport model that made ``tables`` (their ``transport`` field; ``dobashi`` when they name none)."""
    return get(getattr(tables, "transport", "dobashi"))
