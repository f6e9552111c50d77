"""
Transport models
================

Names the transport models of the cloud's multiple scattering (``precompute.transport``,
``shots.<name>.render.transport``):

-   :data:`TRANSPORTS`: the models' names.
-   :func:`get`: the model called ``name``.
-   :func:`of`: the model that made a set of tables.

Each model owns its precompute, its composition for the GA and its direct render behind one interface
(:class:`natscene.scatter.transport.base.Transport`), which the precompute (:mod:`natscene.scatter.tables`), the
fit (:mod:`natscene.fit`) and the shots (:mod:`natscene.scatter.render`) call:

- ``all_orders`` (default, :mod:`.all_orders`): every order of the sun's light and the skylight, in bands of
  orders whose albedo dependence is closed-form (Dobashi 2012 §7's remedies);
- ``dobashi`` (:mod:`.dobashi`): the paper's orders 2..n_m by path tracing plus the ambient term (§4.3);
- :mod:`.base`: the interface both implement.

References
----------
-   Bouthors, A., Neyret, F., Max, N., Bruneton, E., & Crassin, C. (2008). Interactive multiple anisotropic
    scattering in clouds. Proceedings of the 2008 Symposium on Interactive 3D Graphics and Games, 173–182.
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
"""
from __future__ import annotations

from natscene.errors import InputError
from natscene.scatter.transport.base import Transport

__all__ = ["TRANSPORTS", "get", "of"]

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
