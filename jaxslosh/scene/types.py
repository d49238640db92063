"""The validated, immutable scene: plain frozen dataclasses of Python numbers and tuples.

A scene is what `load_scene` returns (see `scene.py` for the loader and its validation rules,
docs/reference/scene.md for the file format). Everything here is static model data: nothing is traced.
Values that `simulate(scene, params=...)` may override are looked up by their dotted TOML path
(`vessel.hydrostatics.gm_t`, `tanks.tank.fill_depth` or `tanks[0].fill_depth`) in `Scene.values()`.
"""
from __future__ import annotations

import abc
import math
from dataclasses import dataclass, field
from typing import Optional, Union, final

from ..fem.mesh import ELEMENT_FORMS, FACE_FORMS  # noqa: F401  (the loader reads them here)
from ..geometry import SHAPES, AbstractShape
from ..solve.schemes import SCHEMES, AbstractScheme
from .liquids import LiquidForm, liquid_form
from .hulls import HULLS, BoxHull, Hull, MeshHull  # noqa: F401  (the scene's types, read from here)
from .seas import WAVES, IrregularSea, JonswapSea, PiersonMoskowitzSea, RegularWaves, Waves  # noqa: F401

#: the six rigid dofs, in the order of every 6-vector and 6 x 6 table
DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")
#: faces of a block ("x-" is x = 0, "z+" is z = size_z)
FACES = ("x-", "x+", "y-", "y+", "z-", "z+")
#: free faces above which a full-order face-normal tank is refused (its blocks are dense), and above
#: which the loader does not choose "rt" by default for a tank without [tanks.reduction]
RT_FULL_FACES = 4000

Vec3 = tuple[float, float, float]
Mat3 = tuple[Vec3, Vec3, Vec3]


class SceneError(ValueError):
    """Bad input: `key` is the dotted path of the offending value, the message names it."""

    def __init__(self, key: str, message: str):
        self.key = key
        super().__init__(f"{key}: {message}" if key else message)


@dataclass(frozen=True)
class Environment:
    gravity: float = 9.81            # m/s^2, >= 0 (0: no gravity, e.g. a torque-free body)
    water_density: float = 1025.0    # kg/m^3, > 0
    depth: Optional[float] = None    # m, > 0: the water depth (the seabed of mooring lines); None: infinite


@dataclass(frozen=True)
class Simulation:
    duration: float                  # s, > 0
    dt: float                        # s, > 0, <= duration
    scheme: str = "hht"              # "newmark" | "hht" | "generalized-alpha"
    alpha: float = 0.0               # HHT: 0 <= alpha <= 1/3
    rho_inf: float = 1.0             # generalized-alpha: 0 <= rho_inf <= 1
    save_every: int = 1              # >= 1
    tolerance: float = 1e-10         # Newton: residual over mass, an acceleration error (m/s^2, rad/s^2)
    max_iterations: int = 25         # Newton iterations per step before the step counts as failed
    chunk: int = 0                   # steps per jitted chunk written to the result (0: automatic)
    substeps: int = 0                # > 1: a step whose Newton iteration fails is retried as this many sub-steps
    linear_solver: str = "auto"      # liquid block: "dense" inverse | "sparse" (sparse.py, factored.py) | "sparse-host" | "auto" by size
    energy_projection: bool = False  # trapezoidal rule only: scale the velocities after each step to the initial energy

    @property
    def n_steps(self) -> int:
        return int(round(self.duration / self.dt))

    def time_scheme(self) -> AbstractScheme:
        """The member of the generalized-alpha family that `scheme`, `alpha` and `rho_inf` name."""
        return SCHEMES[self.scheme].from_settings(self.alpha, self.rho_inf)


@dataclass(frozen=True)
class Hydrostatics:
    waterplane_area: float           # A_w, m^2, > 0
    displaced_volume: float          # m^3, > 0
    gm_t: float                      # m (<= 0 legal, warned)
    gm_l: float                      # m (<= 0 legal, warned)
    moment: str = "conservative"     # "conservative": gradient of a restoring potential | "paper": eq. (36) literally
    model: str = "linear"            # "linear": GM springs (eqs. 33-38) | "nonlinear": pressure on the hull's wetted surface

    @property
    def nonlinear(self) -> bool:
        return self.model == "nonlinear"


@dataclass(frozen=True)
class Initial:
    position: Vec3 = (0.0, 0.0, 0.0)          # m, inertial offset of the COG from equilibrium
    velocity: Vec3 = (0.0, 0.0, 0.0)          # m/s, inertial
    angular_velocity: Vec3 = (0.0, 0.0, 0.0)  # rad/s, body frame
    roll_pitch_yaw: Vec3 = (0.0, 0.0, 0.0)    # rad, initial attitude (Z-Y-X: yaw, then pitch, then roll)


@dataclass(frozen=True)
class Forced:
    """Prescribed motion of the vessel (tank tests, rotating hubs). One rigid dof follows a profile,
    the other five are held at zero, or a record prescribes any of them:
    "harmonic": amplitude * sin(frequency * t + phase), faded in over `ramp` seconds by the C2 ramp
    s - sin(2 pi s) / (2 pi), s = t / ramp (physics/vessel.py smooth_ramp);
    "spin-up" (a rotation dof): the rate grows smoothly from 0 to `rate` over `duration` seconds,
    omega(t) = rate / duration (t - duration / (2 pi) sin(2 pi t / duration)), then stays (the
    Kane-Ryan-Banerjee profile);
    "record" (`file`): sampled surge, sway, heave, roll, pitch, yaw (any of them; scene/record.py),
    interpolated by a natural cubic spline (continuous acceleration); the dofs not given held."""
    dof: str = ""                    # "surge" | "sway" | "heave" | "roll" | "pitch" | "yaw" ("" for a record)
    amplitude: float = 0.0           # m or rad (harmonic)
    frequency: float = 1.0           # rad/s, > 0 (harmonic)
    ramp: float = 0.0                # s, >= 0: the amplitude grows as s - sin(2 pi s) / (2 pi), s = t / ramp
    profile: str = "harmonic"        # "harmonic" | "spin-up" | "record"
    rate: float = 0.0                # rad/s (spin-up: final rate)
    duration: float = 0.0            # s, > 0 (spin-up time)
    phase: float = 0.0               # rad (harmonic)
    file: str = ""                   # record: the file (absolute path)
    times: tuple = ()                # record: the sample times, s, increasing
    columns: tuple = ()              # record: ((dof, samples), ...) in the file's column order


class FloatingBody(abc.ABC):
    """A rigid floating body of the scene: the vessel (`Vessel`, one final) or one of the `[[bodies]]`
    beside it (`Body`, the other), abstract-or-final (docs/design.md). The finals declare these
    fields as their own dataclass fields (their constructors' orders differ); code that takes the
    vessel or a body alike reads them here: its name, its rigid-body mass and inertia about its
    COG, its hydrostatics, initial offsets, hull and hydrodynamic tables, its COG's height above the
    still-water level, its waterplane's `footprint`, and its rest pose in the vessel-at-rest frame."""
    name: str
    mass: float
    inertia: Mat3
    hydrostatics: Optional[Hydrostatics]
    initial: Initial
    hull: Optional["Hull"]
    hydrodynamics: Optional["Hydrodynamics"]
    cog_height: float
    footprint: Optional[tuple]

    @property
    @abc.abstractmethod
    def position(self) -> tuple:
        """(x, y) m of its COG at rest from the vessel's, inertial."""

    @property
    @abc.abstractmethod
    def heading(self) -> float:
        """Its x axis at rest, rad from the inertial X axis."""

    def rest_point(self, point) -> Vec3:
        """A point of its frame (from its COG) at rest: x, y from the vessel's COG at rest along the
        inertial axes, z from the still-water level."""
        c, s = math.cos(self.heading), math.sin(self.heading)
        x, y, z = point
        return (self.position[0] + c * x - s * y, self.position[1] + s * x + c * y, z + self.cog_height)


@final
@dataclass(frozen=True)
class Vessel(FloatingBody):
    mass: float                      # kg, > 0 (everything except tank liquid)
    inertia: Mat3                    # kg m^2 about the COG, body axes, symmetric positive definite
    hydrostatics: Optional[Hydrostatics] = None   # None: no buoyancy (free body)
    initial: Initial = field(default_factory=Initial)
    forced: Optional[Forced] = None  # prescribed motion instead of free motion
    hull: Optional["Hull"] = None    # hull geometry: Froude-Krylov forces, Capytaine (waves, hydrodynamics.py)
    hydrodynamics: Optional["Hydrodynamics"] = None   # added mass, radiation damping, excitation tables
    name: str = "vessel"             # how mooring lines (`body`) name it
    cog_height: float = 0.0          # m, the COG's height above the still-water level at rest
    footprint: Optional[tuple] = None   # (length, beam) m of the waterplane: the bodies' overlap check

    # the vessel at rest is the frame the bodies' places are given in
    @property
    def position(self) -> tuple:
        return (0.0, 0.0)

    @property
    def heading(self) -> float:
        return 0.0


@final
@dataclass(frozen=True)
class Body(FloatingBody):
    """A `[[bodies]]` rigid floating body beside the vessel (docs/guide/bodies-and-connections.md):
    its COG at rest `position` (x, y) horizontally from the vessel's, inertial, and `cog_height`
    above the still-water level; its x axis `heading` rad from the inertial X axis."""
    name: str
    mass: float                      # kg, > 0
    inertia: Mat3                    # kg m^2 about its COG, its body axes
    hydrostatics: Hydrostatics       # linear GM springs about its rest pose
    position: tuple = (0.0, 0.0)     # m
    heading: float = 0.0             # rad
    cog_height: float = 0.0          # m
    initial: Initial = field(default_factory=Initial)   # offsets from its rest pose (attitude after the heading)
    viscous_damping: Optional[tuple] = None   # (6, 6) linear damping, N s/m and N m s, its COG and axes
    hydrodynamics: Optional["Hydrodynamics"] = None   # the vessel's keys: tables, a file (its block of a multibody one)
    footprint: Optional[tuple] = None   # (length, beam) m of the waterplane along its heading: the overlap check
    tanks: tuple = ()                # the [[tanks]] it carries (`tanks.body`), in its frame from its COG
    hull: Optional["Hull"] = None    # [bodies.hull]: the vessel's kinds (scene/hulls.py), in its frame from its COG


@dataclass(frozen=True)
class Connection:
    """A `[[connections]]` hawser, fender or spring between two bodies, or a body and a fixed point
    (docs/guide/bodies-and-connections.md). `ends`: two names, "vessel", a body's or "fixed"
    (second only); `points` one per end in that end's frame from its COG (a fixed end's inertial,
    from the vessel's COG at rest); `curve` ((deflection m, force N), ...) from (0, 0), increasing."""
    name: str
    kind: str                        # "hawser" | "fender" | "spring"
    ends: tuple                      # (str, str)
    points: tuple                    # (Vec3, Vec3)
    length: float                    # m, >= 0
    stiffness: Optional[float] = None   # N/m (None: the curve)
    curve: tuple = ()                # ((deflection, force), ...), starting at (0, 0)
    damping: float = 0.0             # N s/m, >= 0


@dataclass(frozen=True)
class MooringLine:
    """A `[[mooring]]` line (docs/guide/moorings.md): the fairlead in its body's frame (from the
    COG), the anchor inertial (x, y from the vessel's COG at rest, z from the still-water level)."""
    name: str
    fairlead: Vec3
    anchor: Vec3
    length: float                    # m, unstretched, > 0
    weight: float                    # N/m submerged (negative: buoyant)
    ea: float                        # N, > 0
    body: str = "vessel"
    model: str = "catenary"
    seabed_friction: float = 0.0
    anchor_height: float = 0.0       # m above the seabed (anchor z + depth)
    lumped: tuple = ()               # model = "lumped": its lumped-only values, (key, value) pairs (mooring/lumped_term.py)


@dataclass(frozen=True)
class Material:
    young: float                     # Pa, > 0
    poisson: float                   # -1 < nu < 0.5
    density: float                   # kg/m^3, > 0


@dataclass(frozen=True)
class Fluid:
    density: float = 1000.0          # kg/m^3, > 0
    sound_speed: float = 1500.0      # m/s, > 0
    element: str = "stabilized"      # liquid element form: ELEMENT_FORMS (liquid/nodal/model.py) or FACE_FORMS (liquid/face/element.py)
    element_default: str = ""        # why the loader chose `element` when the scene left it out ("" when given)


@dataclass(frozen=True)
class Reduction:
    """`[tanks.reduction]`: the liquid on its first `modes` natural modes plus a static correction
    (reduction.py), instead of every finite-element unknown."""
    modes: int                       # >= 1 natural modes (a degenerate pair is never split)
    static_correction: bool = True   # add the quasi-static response to the rigid body's loads


@dataclass(frozen=True)
class Damping:
    """`[tanks.damping]`: linear damping of the liquid's sloshing modes (liquid/modal_damping.py)."""
    ratio: Union[float, tuple] = 0.0   # every sloshing mode's damping ratio, or one per lowest mode (others 0)
    viscosity: float = 0.0             # m^2/s, >= 0: adds each mode's laminar boundary-layer damping


@dataclass(frozen=True)
class Walls:
    thickness: float                 # m, > 0
    material: Material
    mesh: Optional[tuple[int, int, int]] = None


@dataclass(frozen=True)
class Tank:
    name: str
    origin: Vec3                     # inner min corner in the vessel frame, m
    size: Vec3                       # inner length, breadth, height, m, each > 0
    fill_depth: float                # m, 0 < fill_depth <= size[2]
    mesh: tuple[int, int, int]       # liquid hexahedra along x, y, z, each >= 1
    walls: str = "rigid"             # "rigid" | "elastic"
    fluid: Fluid = field(default_factory=Fluid)
    wall_spec: Optional[Walls] = None   # the [tanks.walls] table when walls = "elastic"
    reduction: Optional[Reduction] = None   # None: full order
    damping: Optional[Damping] = None       # None: an inviscid, undamped liquid
    shape: str = "box"                      # "box" | "prismatic" | "cylinder" | "mesh" (geometry.SHAPES)
    chamfers: tuple = ((0.0, 0.0), (0.0, 0.0))   # prismatic: (width y, height z) of the bottom and top cuts
    axis: str = "x"                         # cylinder: "x", "y" (horizontal) or "z" (vertical)
    file: str = ""                          # mesh: the mesh file (absolute path)
    baffles: tuple = ()                     # geometry.Baffle per [[tanks.baffles]]
    model: str = "fem"                      # "fem" | "multimodal" (liquid/multimodal/term.py)
    modes: int = 6                          # multimodal: free-surface modes (the lowest, whole degenerate groups)
    flow: str = "2d"                        # multimodal: "2d" along a box's length | "3d" (a cylinder's always)
    expansion: str = "exact"                # multimodal: "exact" integrals | "third-order" (liquid/multimodal/expansion.py)

    #: the shape (jaxslosh/geometry), built by the loader from the keys above; a Tank made by hand
    #: gets it from them
    geometry: Optional[AbstractShape] = field(default=None, compare=False, repr=False)

    #: the liquid form its keys choose (scene/liquids.py), made from them at construction: code
    #: elsewhere asks it (or the properties below), not the strings of `model`, `fluid.element`,
    #: `flow`, `expansion`; jaxslosh/liquid maps it to the model that runs it
    form: Optional[LiquidForm] = field(default=None, init=False, compare=False, repr=False)

    # The form's answers, kept here for the code and scripts that ask the tank.
    @property
    def multimodal(self) -> bool:
        """Its liquid is the multimodal one (liquid/multimodal), not a finite-element one."""
        return self.form.multimodal

    @property
    def face_normal(self) -> bool:
        """Its finite-element liquid is the face-normal element (liquid/face), not a nodal one."""
        return self.form.face_normal

    @property
    def three_dimensional(self) -> bool:
        """A multimodal tank's flow is three-dimensional (a cylinder's always), not along x alone."""
        return self.form.three_dimensional

    @property
    def third_order(self) -> bool:
        """A multimodal tank runs its third-order system, not the exact integrals."""
        return self.form.third_order

    def __post_init__(self):
        if self.geometry is None:
            cls = SHAPES[self.shape]
            own = {k: getattr(self, k) for k in ("chamfers", "axis", "file", "baffles")
                   if k in cls.__dataclass_fields__}
            object.__setattr__(self, "geometry", cls(size=tuple(self.size), **own))
        object.__setattr__(self, "form", liquid_form(self))

    @property
    def liquid_volume(self) -> float:
        return self.geometry.volume(self.fill_depth)

    @property
    def liquid_mass(self) -> float:
        return self.fluid.density * self.liquid_volume

    @property
    def wall_mass(self) -> float:
        """Mass of elastic walls (an open box one wall thick around the inner size); 0 for rigid ones,
        whose mass is the vessel's."""
        if self.wall_spec is None:
            return 0.0
        a, b, H = self.size
        t = self.wall_spec.thickness
        return self.wall_spec.material.density * ((a + 2 * t) * (b + 2 * t) * (H + t) - a * b * H)


@dataclass(frozen=True)
class Structure:
    name: str
    origin: Vec3
    size: Vec3
    mesh: tuple[int, int, int]
    attach: str                      # "x-" | "x+" | "y-" | "y+" | "z-" | "z+"
    material: Material
    attach_to: Optional[str] = None  # another structure's name: tie the face to it instead of the vessel
    frame: str = "own"               # "own": its own floating frame, tied by multipliers; "vessel": deformation
                                     # measured in the vessel's frame, the attachment face held (no multipliers)
    stiffening: str = "none"         # "centrifugal": the geometric stiffness of the stress its spin causes


@dataclass(frozen=True)
class Probe:
    name: str
    point: Vec3                      # local coordinates from the owner's origin, m
    tank: Optional[str] = None       # exactly one of tank / structure is set
    structure: Optional[str] = None


# ---- waves and hull hydrodynamics (waves.py, hydrodynamics.py)
# Waves (scene/seas.py) and Hull (scene/hulls.py): an abstract class each, with a final kind per
# value of their `type` key


@dataclass(frozen=True)
class Hydrodynamics:
    """The `[vessel.hydrodynamics]` table: frequency-domain coefficients about the COG, or
    `capytaine = true` to compute them from the hull. Arrays are nested tuples as written."""
    frequencies: tuple = ()          # rad/s, ascending
    added_mass: Optional[tuple] = None            # (n, 6) diagonal or (n, 6, 6)
    damping: Optional[tuple] = None               # radiation damping, same shapes
    added_mass_infinite: Optional[tuple] = None   # (6,) or (6, 6); fitted when absent
    headings: Optional[tuple] = None              # rad, the excitation tables' headings
    excitation_amplitude: Optional[tuple] = None  # (n, headings, 6) or (n, 6): N/m, N m/m
    excitation_phase: Optional[tuple] = None      # same shape, rad
    viscous_damping: Optional[tuple] = None       # (6,) or (6, 6) linear damping added to the radiation
    capytaine: bool = False          # compute added mass, damping, A_inf and excitation with Capytaine
    panel_size: Optional[float] = None            # m, Capytaine's panels (default from the hull)
    memory_order: int = 0            # complex pole pairs per column of the memory fit (0: automatic)
    excitation: str = "auto"         # "auto" | "table" | "froude-krylov"
    base_dir: str = ""               # the scene's folder (a mesh file is relative to it)
    file: str = ""                   # a hydrodynamic database the tables above were read from (hydro/database.py)
    cog: Optional[tuple] = None      # the COG in the database's coordinates (None: its own, or WAMIT's origin)
    length_scale: float = 1.0        # WAMIT's ULEN, m


@dataclass(frozen=True)
class CampaignTable:
    """The `[campaign]` table: what `jaxslosh campaign` and `js.campaign` take when the command line
    (or the call) does not give it (scene/campaign.py reads it). Nothing here changes a run."""
    limits: tuple[tuple[str, float], ...] = ()   # (channel, limit) in the file's order: rad (roll, pitch), m
    headings: tuple[float, ...] | None = None     # rad; None: the template's waves.heading
    seeds: int | None = None                      # per cell and heading; None: 1
    duration: float | None = None                 # s, each case's; None: simulation.duration

    @property
    def limit_map(self) -> dict[str, float]:
        return dict(self.limits)


EFFECTS = ("buoyancy", "liquid", "coriolis", "centrifugal", "gravity_turning", "waves", "radiation")


@dataclass(frozen=True)
class Effects:
    """Switches of the `[effects]` table. An effect is simulated when the scene has what it needs
    (a hydrostatics table, tanks, ...) and its switch is on; the model never traces an effect that
    is off, so switching one off measures what it contributes."""
    buoyancy: bool = True            # restoring force and moments, eqs. (33)-(36)
    liquid: bool = True              # the tank liquid (off: the tanks are empty and carry nothing)
    coriolis: bool = True            # 2 omega x d_dot on the liquid (eq. 19)
    centrifugal: bool = True         # omega x (omega x r) on the liquid (eq. 19)
    gravity_turning: bool = True     # gravity turning with the body as a load on the liquid (eq. 32)
    waves: bool = True               # first-order wave excitation from the [waves] table
    radiation: bool = True           # added mass, radiation damping and memory from [vessel.hydrodynamics]


@dataclass(frozen=True)
class Scene:
    title: str
    environment: Environment
    simulation: Simulation
    vessel: Vessel
    tanks: tuple[Tank, ...] = ()
    structures: tuple[Structure, ...] = ()
    probes: tuple[Probe, ...] = ()
    effects: Effects = field(default_factory=Effects)
    text: str = ""                   # the TOML source, stored in result files
    path: str = ""
    warnings: tuple[str, ...] = ()   # physically doubtful but legal choices, said once at load
    waves: Optional["Waves"] = None  # the [waves] table: incident regular waves or a JONSWAP sea
    campaign: CampaignTable | None = None      # the [campaign] table: a campaign's limits and defaults
    mooring: tuple["MooringLine", ...] = ()    # the [[mooring]] lines
    bodies: tuple["Body", ...] = ()            # the [[bodies]]: rigid floating bodies beside the vessel
    connections: tuple["Connection", ...] = () # the [[connections]]: hawsers, fenders, springs

    def tank(self, name: str) -> Tank:
        for t in self.tanks:
            if t.name == name:
                return t
        raise SceneError("tank", f"no tank named {name!r} (tanks: {', '.join(t.name for t in self.tanks) or 'none'})")

    def structure(self, name: str) -> Structure:
        for s in self.structures:
            if s.name == name:
                return s
        raise SceneError("structure", f"no structure named {name!r}")
