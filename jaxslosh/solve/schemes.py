"""The time-integration schemes: one generalized-alpha family (Arnold & Bruls 2007) covers the
trapezoidal rule (Newmark), HHT-alpha and generalized-alpha (Chung & Hulbert 1993)."""
from __future__ import annotations

from typing import NamedTuple


class Scheme(NamedTuple):
    alpha_m: float
    alpha_f: float
    beta: float
    gamma: float


def make_scheme(name: str, alpha: float = 0.0, rho_inf: float = 1.0) -> Scheme:
    """Newmark (trapezoidal), HHT-alpha (gamma = 1/2 + alpha, beta = (1 + alpha)^2 / 4, PHYSICS.md
    item 7) or generalized-alpha (Chung & Hulbert 1993, by its high-frequency radius rho_inf)."""
    if name == "newmark":
        return Scheme(0.0, 0.0, 0.25, 0.5)
    if name == "hht":
        return Scheme(0.0, alpha, 0.25 * (1.0 + alpha) ** 2, 0.5 + alpha)
    if name == "generalized-alpha":
        am = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0)
        af = rho_inf / (rho_inf + 1.0)
        return Scheme(am, af, 0.25 * (1.0 - am + af) ** 2, 0.5 - am + af)
    raise ValueError(f"unknown scheme {name!r}")
