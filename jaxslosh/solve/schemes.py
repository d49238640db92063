"""The time-integration schemes: one generalized-alpha family (Arnold & Bruls 2007) covers the
trapezoidal rule (Newmark), HHT-alpha and generalized-alpha (Chung & Hulbert 1993). Each member is
a class that owns its constants and the coefficients the step matrix and the preconditioners take
from them, so that no other module writes them out again."""
from __future__ import annotations

import abc
from dataclasses import dataclass
from typing import ClassVar, final

# plain frozen dataclasses, not JAX modules: the scene loader reads the registry below without
# importing JAX (the command line checks a scene before it imports JAX), and a solver holds its
# scheme as a static field (hashable: one compiled loop per scheme)


@dataclass(frozen=True)
class AbstractScheme(abc.ABC):
    """A member of the generalized-alpha family, by its four constants. In the notation of
    solve/integrator.py,

        (1 - alpha_m) a_{n+1} + alpha_m a_n = (1 - alpha_f) acc_{n+1} + alpha_f acc_n
        d_{n+1} = d_n + h v_n + h^2 ((1/2 - beta) a_n + beta a_{n+1})
        v_{n+1} = v_n + h ((1 - gamma) a_n + gamma a_{n+1})"""
    alpha_m: float
    alpha_f: float
    beta: float
    gamma: float

    #: the value of `simulation.scheme` that names it
    name: ClassVar[str] = ""

    @classmethod
    @abc.abstractmethod
    def from_settings(cls, alpha: float = 0.0, rho_inf: float = 1.0) -> "AbstractScheme":
        """The member of the scene's `simulation.alpha` and `simulation.rho_inf` (each reads its own)."""

    @classmethod
    @abc.abstractmethod
    def settings_words(cls, sim) -> str:
        """What a scene's `[simulation]` sets of the scheme, in words (", alpha 0.01"; "" for none)."""

    def c_a(self, h):
        """d acc_{n+1} / d Delta: the mass matrix's factor in the step matrix c_a M + c_v C + K."""
        return (1.0 - self.alpha_m) / ((1.0 - self.alpha_f) * self.beta * h ** 2)

    def c_v(self, h):
        """d v_{n+1} / d Delta: the damping matrix's factor in the step matrix."""
        return self.gamma / (self.beta * h)

    def c_d(self, h):
        """d a_{n+1} / d Delta = 1 / (beta h^2)."""
        return 1.0 / (self.beta * h ** 2)


#: the family's members are AbstractScheme's final classes (solve/linear.py types its solver's field with it)
Scheme = AbstractScheme


@final
@dataclass(frozen=True)
class Newmark(AbstractScheme):
    """The trapezoidal rule (average acceleration): second order, no numerical damping, the
    energy-conserving member (`simulation.energy_projection` needs it)."""
    name: ClassVar[str] = "newmark"

    @classmethod
    def from_settings(cls, alpha: float = 0.0, rho_inf: float = 1.0) -> "Newmark":
        return cls(0.0, 0.0, 0.25, 0.5)

    @classmethod
    def settings_words(cls, sim) -> str:
        return ", energy projection" if sim.energy_projection else ""


@final
@dataclass(frozen=True)
class HHT(AbstractScheme):
    """HHT-alpha: gamma = 1/2 + alpha, beta = (1 + alpha)^2 / 4 (docs/theory.md item 7); alpha > 0
    damps the high frequencies."""
    name: ClassVar[str] = "hht"

    @classmethod
    def from_settings(cls, alpha: float = 0.0, rho_inf: float = 1.0) -> "HHT":
        alpha = float(alpha)
        return cls(0.0, alpha, 0.25 * (1.0 + alpha) ** 2, 0.5 + alpha)

    @classmethod
    def settings_words(cls, sim) -> str:
        return f", alpha {sim.alpha:g}"


@final
@dataclass(frozen=True)
class GeneralizedAlpha(AbstractScheme):
    """Chung & Hulbert (1993) by its high-frequency spectral radius rho_inf (1: no damping)."""
    name: ClassVar[str] = "generalized-alpha"

    @classmethod
    def from_settings(cls, alpha: float = 0.0, rho_inf: float = 1.0) -> "GeneralizedAlpha":
        r = float(rho_inf)
        am, af = (2.0 * r - 1.0) / (r + 1.0), r / (r + 1.0)
        return cls(am, af, 0.25 * (1.0 - am + af) ** 2, 0.5 - am + af)

    @classmethod
    def settings_words(cls, sim) -> str:
        return f", rho_inf {sim.rho_inf:g}"


#: `simulation.scheme`'s values and their members (the scene loader reads this)
SCHEMES = {c.name: c for c in (Newmark, HHT, GeneralizedAlpha)}


def make_scheme(name: str, alpha: float = 0.0, rho_inf: float = 1.0) -> AbstractScheme:
    """The scheme of the scene file's `simulation.scheme` (with its `alpha` or `rho_inf`)."""
    if name not in SCHEMES:
        raise ValueError(f"unknown scheme {name!r}")
    return SCHEMES[name].from_settings(alpha, rho_inf)
