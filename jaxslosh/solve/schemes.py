"""The time-integration schemes: one generalized-alpha family (Arnold & Bruls 2007) covers the
trapezoidal rule (Newmark), HHT-alpha and generalized-alpha (Chung & Hulbert 1993). Each member is
a class that owns its constants and the coefficients the step matrix and the preconditioners take
from them, so that no other module writes them out again."""
from __future__ import annotations

import equinox as eqx


class Scheme(eqx.Module):
    """A member of the generalized-alpha family, by its four constants (static: one compiled loop
    per scheme). In the notation of solve/integrator.py,

        (1 - alpha_m) a_{n+1} + alpha_m a_n = (1 - alpha_f) acc_{n+1} + alpha_f acc_n
        d_{n+1} = d_n + h v_n + h^2 ((1/2 - beta) a_n + beta a_{n+1})
        v_{n+1} = v_n + h ((1 - gamma) a_n + gamma a_{n+1})"""
    alpha_m: float
    alpha_f: float
    beta: float
    gamma: float

    name = "generalized-alpha"

    def c_a(self, h):
        """d acc_{n+1} / d Delta: the mass matrix's factor in the step matrix c_a M + c_v C + K."""
        return (1.0 - self.alpha_m) / ((1.0 - self.alpha_f) * self.beta * h ** 2)

    def c_v(self, h):
        """d v_{n+1} / d Delta: the damping matrix's factor in the step matrix."""
        return self.gamma / (self.beta * h)

    def c_d(self, h):
        """d a_{n+1} / d Delta = 1 / (beta h^2)."""
        return 1.0 / (self.beta * h ** 2)


class Newmark(Scheme):
    """The trapezoidal rule (average acceleration): second order, no numerical damping, the
    energy-conserving member (`simulation.energy_projection` needs it)."""
    name = "newmark"

    def __init__(self):
        self.alpha_m, self.alpha_f, self.beta, self.gamma = 0.0, 0.0, 0.25, 0.5


class HHT(Scheme):
    """HHT-alpha: gamma = 1/2 + alpha, beta = (1 + alpha)^2 / 4 (docs/theory.md item 7); alpha > 0
    damps the high frequencies."""
    name = "hht"

    def __init__(self, alpha: float = 0.0):
        alpha = float(alpha)
        self.alpha_m, self.alpha_f, self.beta, self.gamma = 0.0, alpha, 0.25 * (1.0 + alpha) ** 2, 0.5 + alpha


class GeneralizedAlpha(Scheme):
    """Chung & Hulbert (1993) by its high-frequency spectral radius rho_inf (1: no damping)."""
    name = "generalized-alpha"

    def __init__(self, rho_inf: float = 1.0):
        r = float(rho_inf)
        am, af = (2.0 * r - 1.0) / (r + 1.0), r / (r + 1.0)
        self.alpha_m, self.alpha_f, self.beta, self.gamma = am, af, 0.25 * (1.0 - am + af) ** 2, 0.5 - am + af


SCHEMES = {"newmark": Newmark, "hht": HHT, "generalized-alpha": GeneralizedAlpha}


def make_scheme(name: str, alpha: float = 0.0, rho_inf: float = 1.0) -> Scheme:
    """The scheme of the scene file's `simulation.scheme` (with its `alpha` or `rho_inf`)."""
    if name == "newmark":
        return Newmark()
    if name == "hht":
        return HHT(alpha)
    if name == "generalized-alpha":
        return GeneralizedAlpha(rho_inf)
    raise ValueError(f"unknown scheme {name!r}")
