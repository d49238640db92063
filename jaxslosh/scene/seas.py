"""The kinds of `[waves]`: an abstract `Waves` and one final class per value of its `type` key
(`WAVES`, the registry the loader reads): a regular wave, and the JONSWAP and Pierson-Moskowitz
seas. Code that uses a sea asks it (its height and the key that traces it, its frequency band,
its components, its words) instead of asking which kind it is. The fields are one record for all
kinds (a kind leaves the others' at their defaults), so that `dataclasses.replace` and the scene
comparison see the same keys as before the kinds. docs/reference/scene.md has the keys.
"""
from __future__ import annotations

import abc
from dataclasses import dataclass, field
from typing import ClassVar, Optional, final

import numpy as np

from ..hydro.spectra import Components, drawn_components, jonswap, pierson_moskowitz


@dataclass(frozen=True)
class Waves(abc.ABC):
    """The `[waves]` table: a regular wave or an irregular sea (hydro/spectra.py has the conventions)."""
    type: str = field(default="", init=False)   # the `type` key's value (each final kind sets its own)
    heading: float = 0.0             # rad, the direction the waves travel to, from +X towards +Y
    amplitude: float = 0.0           # m (regular)
    omega: float = 0.0               # rad/s (regular; the scene gives `period` or `frequency`)
    phase: float = 0.0               # rad (regular): eta = amplitude cos(omega t + phase) at the origin
    hs: float = 0.0                  # m, significant wave height (jonswap)
    tp: float = 0.0                  # s, peak period (jonswap)
    gamma: float = 3.3               # peak enhancement (jonswap), >= 1
    seed: int = 0                    # random phases and frequencies (jonswap)
    components: int = 100            # regular components (jonswap), >= 1
    omega_range: tuple[float, float] = (0.0, 0.0)   # rad/s (jonswap; default 0.5 to 3 times the peak frequency)
    ramp: float = 0.0                # s, the forces fade in as (1 - cos(pi t / ramp)) / 2
    depth: Optional[float] = None    # m, water depth (None: deep water)
    spreading: float = 0.0           # cos-2s directional spreading exponent s (irregular seas); 0: long-crested
    directions: int = 1              # headings the spreading is discretised into (odd: one on the mean heading)

    #: whether the sea is drawn from a spectrum (a campaign's template must be)
    irregular: ClassVar[bool] = False
    #: the dotted key of the value the forces are proportional to (`params` may trace it)
    height_key: ClassVar[str] = ""

    @property
    @abc.abstractmethod
    def height(self) -> float:
        """The value the forces are proportional to: the amplitude (regular) or Hs (irregular)."""

    @property
    @abc.abstractmethod
    def band(self) -> tuple[float, float]:
        """(lowest, highest) frequency of the sea's components, rad/s: a regular wave's twice."""

    @abc.abstractmethod
    def wave_components(self) -> Components:
        """The regular components the sea is the sum of (hydro/spectra.py `components`)."""

    @abc.abstractmethod
    def describe(self) -> str:
        """The sea's kind and size in a few words."""


@final
@dataclass(frozen=True)
class RegularWaves(Waves):
    """`type = "regular"`: eta = amplitude cos(omega t + phase) at the origin."""
    type: str = field(default="regular", init=False)
    height_key: ClassVar[str] = "waves.amplitude"

    @property
    def height(self) -> float:
        return self.amplitude

    @property
    def band(self) -> tuple[float, float]:
        return (self.omega, self.omega)

    def wave_components(self) -> Components:
        return Components(np.array([self.omega]), np.array([self.amplitude]), np.array([self.phase]),
                          float(self.heading))

    def describe(self) -> str:
        return f"regular, amplitude {self.amplitude:g} m, {self.omega:.4g} rad/s"


@dataclass(frozen=True)
class IrregularSea(Waves):
    """A sea drawn from a spectrum (`spectrum`): Hs, Tp, the frequency range, seed and spreading."""
    irregular: ClassVar[bool] = True
    height_key: ClassVar[str] = "waves.hs"

    @property
    def height(self) -> float:
        return self.hs

    @property
    def band(self) -> tuple[float, float]:
        return tuple(self.omega_range)

    @abc.abstractmethod
    def spectrum(self, omega):
        """The one-sided spectral density S(w), m^2 s / rad, at frequencies omega."""

    def wave_components(self) -> Components:
        return drawn_components(self)

    @abc.abstractmethod
    def spectrum_words(self) -> str:
        """The spectrum's name and parameters."""

    def describe(self) -> str:
        return (f"{self.spectrum_words()}, {self.components} components, seed {self.seed}"
                + (f", cos-2s spreading s = {self.spreading:g} over {self.directions} headings"
                   if self.spreading > 0 else ""))


@final
@dataclass(frozen=True)
class JonswapSea(IrregularSea):
    """`type = "jonswap"`: the JONSWAP spectrum of Hs, Tp and the peak enhancement gamma."""
    type: str = field(default="jonswap", init=False)

    def spectrum(self, omega):
        return jonswap(omega, self.hs, self.tp, self.gamma)

    def spectrum_words(self) -> str:
        return f"JONSWAP Hs {self.hs:g} m, Tp {self.tp:g} s, gamma {self.gamma:g}"


@final
@dataclass(frozen=True)
class PiersonMoskowitzSea(IrregularSea):
    """`type = "pierson-moskowitz"`: the fully developed sea of Hs and Tp (JONSWAP with gamma = 1)."""
    type: str = field(default="pierson-moskowitz", init=False)

    def spectrum(self, omega):
        return pierson_moskowitz(omega, self.hs, self.tp)

    def spectrum_words(self) -> str:
        return f"Pierson-Moskowitz Hs {self.hs:g} m, Tp {self.tp:g} s"


#: the `type` key's values and their kinds (the loader reads this)
WAVES = {"regular": RegularWaves, "jonswap": JonswapSea, "pierson-moskowitz": PiersonMoskowitzSea}
