"""
Genetic algorithm for the cloud parameters
==========================================

Defines the simple genetic algorithm of Dobashi et al. (2012, §4.2 and §5) after Goldberg (1989):

-   :func:`run_ga`: minimise O over the parameters; the ranked distinct sets in a :class:`FitResult`.
-   :class:`Codec`: parameter values to concatenated ``bits``-bit strings and back.
-   :class:`UnitBox`: the map between parameter values and the unit box (log scale for :data:`LOG_PARAMS`).
-   :func:`roulette`, :func:`linear_scaling`, :func:`two_point_crossover`, :func:`mutate`: the operators.
-   :func:`fit_params`: the parameters a transport model fits; :data:`PARAMS`, :data:`DEFAULT_RANGES`.
-   :class:`Candidate`: one ranked parameter set.

Following Goldberg's simple GA as the paper does: each parameter (L_in, g, extinction, beta, L_amb) is
quantised to ``bits`` = 32 bits over its range (value = lo + (hi - lo) * k / (2^bits - 1); the extinction in
1/m, which spans two decades, on a log scale: value = lo (hi / lo)^(k / (2^bits - 1))) and the five
bit strings are concatenated into one gene of 160 bits; the initial population of n = 20 individuals is
random; fitness is ``1 / (O + 1)`` (maximum 1); parents are drawn by fitness-proportionate (roulette-wheel)
selection (after Goldberg's linear fitness scaling with c_mult = 2, part of his simple GA, unless
``scaling="none"``: 1/(O+1) only spans [1/3, 1] so unscaled selection barely prefers good individuals), mated by two-point crossover with probability ``crossover_rate`` and every bit of a child is
flipped with probability ``mutation_rate`` (bit mutation); elitist selection carries the best individual
of each iteration unchanged into the next. The search stops when the best O < epsilon_O (0.5), when the
best parameters are unchanged for n_suc (20) successive iterations, or after n_max (100) iterations (§5).

The paper gives neither crossover nor mutation rate ("we chose these genetic operators experimentally");
the defaults here, crossover 0.8 and mutation 0.02 per bit (about 3 flipped bits per 160-bit child), with
linear scaling, are those that gave the lowest and least scattered final O on a synthetic target
(docs/stages/fit.md, "Measured"). Every evaluated individual is kept
in an archive, from which the top-k *distinct* parameter sets are ranked (two sets are the same when every
parameter differs by less than ``distinct_tol`` of its range) for the user to choose from (§1, §4).

References
----------
-   Dobashi, Y., Iwasaki, W., Ono, A., Yamamoto, T., Yue, Y., & Nishita, T. (2012). An inverse problem approach
    for automatically adjusting the parameters for rendering clouds using photographs. ACM Transactions on
    Graphics, 31(6).
-   Goldberg, D. E. (1989). Genetic Algorithms in Search, Optimization and Machine Learning. Addison-Wesley.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from natscene.config import complete_section

__all__ = ["PARAMS", "LOG_PARAMS", "DEFAULT_RANGES", "fit_params", "UnitBox", "Candidate", "FitResult", "Codec",
           "roulette", "linear_scaling", "two_point_crossover", "mutate", "run_ga"]

PARAMS = ("L_in", "g", "extinction", "beta", "L_amb")       # every parameter a transport may fit (the paper's five)
LOG_PARAMS = frozenset({"extinction"})                      # searched on a log scale (lo > 0)


def fit_params(transport: str) -> tuple:
    """The GA's parameters for a transport model (:attr:`natscene.scatter.transport.base.Transport.fit_params`)."""
    from natscene.scatter.transport import get
    return get(transport).fit_params


#: parameter -> (min, max): the schema's defaults of ``fit.ranges`` (workflow/schemas/fit.schema.yaml)
DEFAULT_RANGES = {k: tuple(v) for k, v in complete_section({}, "fit.schema.yaml", ("ranges",), "fit.ranges").items()}


class UnitBox:
    """The map between parameter values (P, n) in ``names`` order and the unit box [0, 1]^n the searches
    move in: linear over each range, logarithmic for :data:`LOG_PARAMS` (whose ``lo`` must be > 0)."""

    def __init__(self, names: Sequence[str], ranges: dict):
        self.names = tuple(names)
        self.lo = np.array([ranges[p][0] for p in names], np.float64)
        self.hi = np.array([ranges[p][1] for p in names], np.float64)
        if np.any(self.hi < self.lo):
            raise ValueError(f"empty parameter range: {list(zip(self.lo, self.hi))}")
        self.log = np.array([p in LOG_PARAMS for p in names])
        if np.any(self.log & (self.lo <= 0)):
            bad = [p for p, lg, lo in zip(names, self.log, self.lo) if lg and lo <= 0]
            raise ValueError(f"log-scaled parameters need a range above 0: {bad}")
        self._a = np.where(self.log, np.log(np.where(self.log, self.lo, 1.0)), self.lo)
        b = np.where(self.log, np.log(np.where(self.log, self.hi, 1.0)), self.hi)
        self._span = b - self._a

    def from_unit(self, u: np.ndarray) -> np.ndarray:
        x = self._a + self._span * np.asarray(u, np.float64)
        return np.where(self.log, np.exp(x), x)

    def to_unit(self, values: np.ndarray) -> np.ndarray:
        v = np.asarray(values, np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            x = np.where(self.log, np.log(np.maximum(v, np.where(self.log, self.lo, 1.0))), v)
        span = np.where(self._span > 0, self._span, 1.0)
        return np.clip((x - self._a) / span, 0.0, 1.0)


@dataclass
class Candidate:
    values: dict          # parameter name -> value
    objective: float
    kappa: np.ndarray     # (3,) kappa_a per channel found by the line search
    iteration: int


@dataclass
class FitResult:
    best: Candidate
    ranked: list                       # top-k distinct Candidates, best first
    best_history: np.ndarray           # best O per iteration (iteration 0 = initial population)
    mean_history: np.ndarray           # mean O of the population per iteration
    iterations: int
    evaluations: int
    reason: str                        # why the search stopped
    archive_values: np.ndarray = field(repr=False, default=None)  # (E, 5) every evaluated parameter set
    archive_objective: np.ndarray = field(repr=False, default=None)


class Codec:
    """Quantise parameter vectors to concatenated ``bits``-bit strings and back."""

    def __init__(self, box: UnitBox, bits: int = 32):
        if not 1 <= bits <= 52:
            raise ValueError("bits must be in 1..52")
        self.box = box
        self.bits = bits
        self.n_params = len(box.lo)
        self.length = bits * self.n_params
        self._weights = (2.0 ** np.arange(bits - 1, -1, -1)).astype(np.float64)  # MSB first

    def decode(self, genes: np.ndarray) -> np.ndarray:
        """Bit strings (P, n_params * bits) uint8 -> parameter values (P, n_params)."""
        g = np.asarray(genes, np.float64).reshape(len(genes), self.n_params, self.bits)
        k = g @ self._weights
        return self.box.from_unit(k / (2.0 ** self.bits - 1))

    def encode(self, values: np.ndarray) -> np.ndarray:
        """Parameter values (P, n_params) -> nearest bit strings (P, n_params * bits) uint8."""
        v = np.asarray(values, np.float64)
        k = np.rint(self.box.to_unit(v) * (2.0 ** self.bits - 1)).astype(np.uint64)
        shifts = np.arange(self.bits - 1, -1, -1, dtype=np.uint64)
        bits = (k[..., None] >> shifts) & np.uint64(1)
        return bits.reshape(len(v), -1).astype(np.uint8)


def roulette(fitness: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """Fitness-proportionate selection of ``n`` indices (Goldberg's roulette wheel)."""
    f = np.asarray(fitness, np.float64)
    cum = np.cumsum(f)
    return np.minimum(np.searchsorted(cum, rng.random(n) * cum[-1], side="right"), len(f) - 1)


def linear_scaling(fitness: np.ndarray, c_mult: float = 2.0) -> np.ndarray:
    """Goldberg's linear fitness scaling (1989, ch. 3): f' = a f + b with mean f' = mean f and
    max f' = c_mult * mean f, or, where that would make the worst negative, min f' = 0."""
    f = np.asarray(fitness, np.float64)
    avg, fmax, fmin = f.mean(), f.max(), f.min()
    if fmax - avg <= 1e-12 * max(avg, 1e-300):
        return np.ones_like(f)
    if fmin > (c_mult * avg - fmax) / (c_mult - 1.0):
        a = (c_mult - 1.0) * avg / (fmax - avg)
        b = avg * (fmax - c_mult * avg) / (fmax - avg)
    else:
        a = avg / (avg - fmin)
        b = -fmin * avg / (avg - fmin)
    return np.maximum(a * f + b, 0.0)


def two_point_crossover(a: np.ndarray, b: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Swap the segment between two random cut points of parent rows a, b (each (M, L)); vectorised."""
    m, length = a.shape
    cuts = np.sort(rng.integers(0, length + 1, size=(m, 2)), axis=1)
    pos = np.arange(length)
    seg = (pos >= cuts[:, :1]) & (pos < cuts[:, 1:])
    return np.where(seg, b, a), np.where(seg, a, b)


def mutate(genes: np.ndarray, rate: float, rng: np.random.Generator) -> np.ndarray:
    """Flip every bit independently with probability ``rate``."""
    flips = rng.random(genes.shape) < rate
    return genes ^ flips.astype(np.uint8)


def _distinct_top(units: np.ndarray, objective: np.ndarray, k: int, tol: float) -> list[int]:
    """Indices of the best ``k`` sets that differ from each other by more than ``tol`` in some unit-box
    coordinate (a fraction of the range; of the decades for a log-scaled parameter)."""
    order = np.argsort(objective, kind="stable")
    chosen: list[int] = []
    for i in order:
        if any(np.all(np.abs(units[i] - units[j]) <= tol) for j in chosen):
            continue
        chosen.append(int(i))
        if len(chosen) == k:
            break
    return chosen


def run_ga(evaluate: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
           ranges: dict | None = None, population: int = 20, bits: int = 32, crossover_rate: float = 0.8,
           mutation_rate: float = 0.02, epsilon_o: float = 0.5, n_suc: int = 20, n_max: int = 100,
           top_k: int = 10, distinct_tol: float = 0.01, scaling: str = "linear", c_mult: float = 2.0,
           seed: int = 0, progress: Callable[[int, float, float], None] | None = None,
           names: tuple = PARAMS) -> FitResult:
    """Minimise O with the GA. ``evaluate(values (P, n)) -> (O (P,), kappa (P, 3))``; columns in ``names`` order.

    ``n_max`` counts iterations after the initial population; ``epsilon_o <= 0`` or ``n_suc <= 0`` disable
    those criteria (e.g. to force n_max iterations as in §5.1).
    """
    ranges = {**DEFAULT_RANGES, **(ranges or {})}
    codec = Codec(UnitBox(names, ranges), bits)
    if scaling not in ("linear", "none"):
        raise ValueError(f"scaling must be 'linear' or 'none', got {scaling!r}")
    if population < 2:
        raise ValueError("population must be >= 2")
    rate = float(mutation_rate)
    rng = np.random.default_rng(seed)

    genes = rng.integers(0, 2, size=(population, codec.length), dtype=np.uint8)
    values = codec.decode(genes)
    obj, kap = evaluate(values)
    obj = np.asarray(obj, np.float64)
    arch_v, arch_o, arch_k, arch_it = [values], [obj], [np.asarray(kap)], [np.zeros(population, int)]
    best_hist, mean_hist = [obj.min()], [obj.mean()]
    b = int(np.argmin(obj))
    elite_gene, elite_o, elite_k = genes[b].copy(), obj[b], np.asarray(kap)[b]
    unchanged, it, reason = 0, 0, "n_max"
    if progress:
        progress(0, float(elite_o), float(obj.mean()))
    while True:
        if epsilon_o > 0 and elite_o < epsilon_o:
            reason = "epsilon_O"
            break
        if n_suc > 0 and unchanged >= n_suc:
            reason = "n_suc"
            break
        if it >= n_max:
            reason = "n_max"
            break
        it += 1
        fitness = 1.0 / (obj + 1.0)
        if scaling == "linear":
            fitness = linear_scaling(fitness, c_mult)
        n_child = population - 1  # the elite fills the last place
        n_pairs = (n_child + 1) // 2
        pa = genes[roulette(fitness, n_pairs, rng)]
        pb = genes[roulette(fitness, n_pairs, rng)]
        ca, cb = two_point_crossover(pa, pb, rng)
        cross = rng.random(n_pairs) < crossover_rate
        ca = np.where(cross[:, None], ca, pa)
        cb = np.where(cross[:, None], cb, pb)
        children = mutate(np.concatenate([ca, cb])[:n_child], rate, rng)
        c_values = codec.decode(children)
        c_obj, c_kap = evaluate(c_values)
        c_obj = np.asarray(c_obj, np.float64)
        genes = np.concatenate([elite_gene[None], children])
        obj = np.concatenate([[elite_o], c_obj])
        arch_v.append(c_values), arch_o.append(c_obj), arch_k.append(np.asarray(c_kap))
        arch_it.append(np.full(n_child, it))
        b = int(np.argmin(c_obj))
        if c_obj[b] < elite_o:
            elite_gene, elite_o, elite_k = children[b].copy(), c_obj[b], np.asarray(c_kap)[b]
            unchanged = 0
        else:
            unchanged += 1
        best_hist.append(elite_o)
        mean_hist.append(obj.mean())
        if progress:
            progress(it, float(elite_o), float(obj.mean()))

    av, ao = np.concatenate(arch_v), np.concatenate(arch_o)
    ak, ait = np.concatenate(arch_k), np.concatenate(arch_it)
    idx = _distinct_top(codec.box.to_unit(av), ao, top_k, distinct_tol)
    ranked = [Candidate(dict(zip(names, av[i].tolist())), float(ao[i]), ak[i], int(ait[i])) for i in idx]
    return FitResult(ranked[0], ranked, np.array(best_hist), np.array(mean_hist), it, len(ao), reason, av, ao)
