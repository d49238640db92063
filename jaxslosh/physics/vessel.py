"""The vessel's own terms: the hull's rigid-body inertia, the weight of a vessel that nothing holds
up, buoyancy (eqs. 33-38), and a prescribed motion of the hull instead of a free one (a term that
prescribes the vessel's rows; a free hull has none)."""
from __future__ import annotations

import abc
from typing import ClassVar, Optional, final

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .about import About
from .kinematics import mv3, rotation_matrix, tv3
from .terms import AbstractTerm, Config, Kin, Rows

#: the rigid dofs' names, in the order of the rigid rows
DOF_NAMES = ("surge", "sway", "heave", "roll", "pitch", "yaw")

# eq. (36): q^T A_phi q = 2 (q0 q1 + q2 q3) = sin(roll) cos(pitch), q^T A_theta q = 2 (q0 q2 - q1 q3)
A_PHI = np.array([[0, 1, 0, 0], [1, 0, 0, 0], [0, 0, 0, 1], [0, 0, 1, 0]], dtype=float)
A_THETA = np.array([[0, 0, 1, 0], [0, 0, 0, -1], [1, 0, 0, 0], [0, -1, 0, 0]], dtype=float)


class RigidBody(AbstractTerm):
    """The hull's inertia in the floating frame at the ship's COG (eqs. 14-16). The scene's mass and
    inertia are the whole ship's but the liquid; flexible structures and elastic walls carry their
    own mass in the model, so the hull is the ship less them, and its COG lies off the frame origin
    by S / mass (S: its first moment, zero without such parts; eq. 14 with r_G)."""
    mass: jax.Array
    inertia: jax.Array                  # (3, 3) about the frame origin, body axes
    S: Optional[jax.Array] = None       # (3,) first moment about the frame origin, kg m (None: zero)

    def rows(self, k: Kin) -> Rows:
        a0, alpha = k.a6[:3], k.a6[3:6]
        w = k.omega
        r_t = self.mass * a0
        r_r = mv3(self.inertia, alpha) + jnp.cross(w, mv3(self.inertia, w))
        if self.S is not None:
            S = self.S
            r_t = r_t + mv3(k.A, jnp.cross(alpha, S) + jnp.cross(w, jnp.cross(w, S)))
            r_r = r_r + jnp.cross(S, tv3(k.A, a0))
        return Rows(jnp.concatenate([r_t, r_r]))

    def kinetic(self, k: Kin):
        V0, w = k.V0, k.omega
        T = 0.5 * self.mass * V0 @ V0 + 0.5 * w @ self.inertia @ w
        return T if self.S is None else T + V0 @ (k.A @ jnp.cross(w, self.S))

    def mass_scale(self):
        return jnp.concatenate([jnp.full(3, self.mass), jnp.diag(self.inertia)])

    def describe(self) -> tuple:
        return (("rigid-body inertia", "vessel: 6 unknowns, rotations on the group (|q| = 1 exactly)"),)


class Weight(AbstractTerm):
    """Gravity on the whole vessel, liquid included, when no hydrostatics hold it up: mass M, first
    moment S of its rigid parts about the frame origin (the deformed liquid's share is the liquid
    term's). With hydrostatics the weight is balanced by the displaced water and this term is absent."""
    mass: jax.Array
    S: jax.Array
    gravity: jax.Array
    about: About = eqx.field(static=True, default=About())     # what holds the vessel up, if anything

    def rows(self, k: Kin) -> Rows:
        g_vec = jnp.array([0.0, 0.0, -self.gravity])
        return Rows(jnp.concatenate([-self.mass * g_vec, -jnp.cross(self.S, k.g_b)]))

    def potential(self, k: Kin):
        return self.mass * self.gravity * k.c.X0[2] - k.g_b @ self.S

    def describe(self) -> tuple:
        return self.about.lines


class AbstractRestoring(AbstractTerm):
    """Linear hydrostatic restoring about the initial equilibrium (eqs. 33-36): the heave force of
    eq. (35) and a restoring moment of the final kind's form (`vessel.hydrostatics.moment`,
    RESTORING_FORMS). The scene's table of the values is scene.types.Hydrostatics."""
    rho_w: jax.Array
    gravity: jax.Array
    waterplane_area: jax.Array
    displaced_volume: jax.Array
    gm_t: jax.Array
    gm_l: jax.Array

    def force(self, X0):
        """Eq. (35) in the inertial frame: F_z = -rho g A_w (Z0 - Z0^0), equilibrium at Z0^0 = 0."""
        return jnp.array([0.0, 0.0, -self.rho_w * self.gravity * self.waterplane_area * X0[2]])

    def moment_paper(self, q):
        """Eq. (36), body frame."""
        k = self.rho_w * self.gravity * self.displaced_volume
        return -k * jnp.array([self.gm_t * (q @ A_PHI @ q), self.gm_l * (q @ A_THETA @ q), 0.0])

    def restoring_potential(self, X0, q):
        """Restoring energy. The moment part, k_T g_y^2 + k_L g_x^2 over (1 + g_z) with g = A^T e_z,
        is 1/2 (k_T roll^2 + k_L pitch^2) to second order, exact for pure roll and pure pitch, and
        its gradient is eq. (36) exactly when GM_T = GM_L (eq. (36) is not conservative otherwise)."""
        k = self.rho_w * self.gravity * self.displaced_volume
        g = rotation_matrix(q)[2]
        heave = 0.5 * self.rho_w * self.gravity * self.waterplane_area * X0[2] ** 2
        return heave + k * (self.gm_t * g[1] ** 2 + self.gm_l * g[0] ** 2) / (1.0 + g[2])

    #: the value of `vessel.hydrostatics.moment` that names the form
    form: ClassVar[str] = ""

    @abc.abstractmethod
    def moment(self, q):
        """The restoring moment (body frame) of the form."""

    def moment_conservative(self, q):
        """The moment of the conservative form: minus the derivative of the potential along
        body-frame rotations, written out (a JAX gradient inside
        the residual would be linearised and transposed again in every Newton preconditioner):
        with g = A^T e_z, a body rotation d theta changes g by g x d theta, so M = g x dV/dg.
        tests/physics/test_vessel.py checks it against the gradient of `restoring_potential`."""
        k = self.rho_w * self.gravity * self.displaced_volume
        g = rotation_matrix(q)[2]
        D = 1.0 + g[2]
        N = self.gm_t * g[1] ** 2 + self.gm_l * g[0] ** 2
        dV_dg = k * jnp.array([2.0 * self.gm_l * g[0] / D, 2.0 * self.gm_t * g[1] / D, -N / D ** 2])
        return jnp.cross(g, dV_dg)

    def rows(self, k: Kin) -> Rows:
        return Rows(jnp.concatenate([-self.force(k.c.X0), -self.moment(k.c.q)]))

    def potential(self, k: Kin):
        return self.restoring_potential(k.c.X0, k.c.q)

    def describe(self) -> tuple:
        return (("buoyancy", f"restoring force and moments of eqs. (33)-(36), moment form {self.form!r}"),)


@final
class ConservativeRestoring(AbstractRestoring):
    """The restoring moment the gradient of the restoring potential (`vessel.hydrostatics.moment =
    "conservative"`): a run without damping conserves its energy."""
    form: ClassVar[str] = "conservative"

    def moment(self, q):
        return self.moment_conservative(q)


@final
class PaperRestoring(AbstractRestoring):
    """The restoring of eqs. (33)-(36) with the moment of eq. (36) literally
    (`vessel.hydrostatics.moment = "paper"`): not the gradient of a potential when GM_T != GM_L, so
    a run's energy is not conserved with it."""
    form: ClassVar[str] = "paper"

    def moment(self, q):
        return self.moment_paper(q)


#: `vessel.hydrostatics.moment`'s values and their terms (the scene loader checks the key against
#: scene/hull.py MOMENTS, below this layer; tests/docs/test_variants.py keeps the two the same)
RESTORING_FORMS = {c.form: c for c in (ConservativeRestoring, PaperRestoring)}


def smooth_ramp(s):
    """0 before s = 0, 1 after s = 1, and s - sin(2 pi s) / (2 pi) between: its value, slope
    (1 - cos 2 pi s) and curvature (2 pi sin 2 pi s) are continuous at both ends. The rigid rows
    prescribe the second derivative of the motion, so a ramp whose curvature jumps (the cosine
    ramp (1 - cos pi s) / 2) puts a jump into the prescribed acceleration; the time scheme
    integrates it with an O(dt) error that stays in the velocity and makes the position drift
    linearly after the ramp (issue 21: 25 um in 12 s of a 1 mm surge at dt = 0.01 s)."""
    s = jnp.clip(s, 0.0, 1.0)
    return s - jnp.sin(2.0 * jnp.pi * s) / (2.0 * jnp.pi)


class AbstractPrescribedMotion(AbstractTerm):
    """A hull whose six rigid coordinates are given functions of time (`[vessel.forced]`): a term
    that prescribes the vessel's motion (terms.py, `prescribes`). Its rows are the vessel's six rows
    of the step: the prescribed accelerations, scaled by the rigid masses like the free rows, in place
    of every other term's share (the vessel's equations of motion are replaced by the constraint);
    positions and velocities follow by the scheme from the prescribed initial state (`start`). A
    scene without forced motion has no such term. The coordinates are surge, sway, heave (the COG's
    inertial position, m) and roll, pitch, yaw (Z-Y-X angles, rad); the body angular velocity is
    their rates turned into the body frame."""

    @abc.abstractmethod
    def coordinates(self, t):
        """(6,) surge, sway, heave, roll, pitch, yaw at time t."""

    def rows(self, k: Kin) -> Rows:
        """No share of the sum: the vessel's rows are replaced by `prescribed_rows`."""
        return Rows(jnp.zeros(6))

    def prescribes(self) -> bool:
        return True

    def prescribed_rows(self, a6, t, scale):
        return scale() * (a6 - self.accelerations(t))

    def start(self, c0: Config, v0):
        """The vessel's position and rigid velocities at t = 0 prescribed (its attitude is the
        System's q_ref, which the build takes from `coordinates(0)`)."""
        t0 = jnp.zeros(())
        return c0._replace(X0=self.coordinates(t0)[:3]), v0.at[:6].set(self.rates(t0))

    def rates(self, t):
        """Prescribed (dX0/dt inertial, omega body) at time t: omega = E(roll, pitch) (roll, pitch,
        yaw)' for A = Rz(yaw) Ry(pitch) Rx(roll); one angle alone gives its own rate exactly."""
        x, v = jax.jvp(self.coordinates, (t,), (jnp.ones_like(t),))
        phi, theta = x[3], x[4]
        dphi, dtheta, dpsi = v[3], v[4], v[5]
        sp, cp, st, ct = jnp.sin(phi), jnp.cos(phi), jnp.sin(theta), jnp.cos(theta)
        omega = jnp.stack([dphi - dpsi * st, dtheta * cp + dpsi * ct * sp, -dtheta * sp + dpsi * ct * cp])
        return jnp.concatenate([v[:3], omega])

    def accelerations(self, t):
        """(d2X0/dt2, d omega/dt) at time t: the time derivative of `rates`."""
        return jax.jvp(self.rates, (t,), (jnp.ones_like(t),))[1]


class HarmonicMotion(AbstractPrescribedMotion):
    """One rigid dof at amplitude sin(frequency t + phase), faded in over `ramp` by `smooth_ramp`
    (C2: no jump in the acceleration); the others held at zero. Amplitude, frequency and phase are
    leaves of the model (traceable: `vessel.forced.amplitude`, `.frequency`, `.phase`)."""
    dof: int = eqx.field(static=True)      # 0-2 surge, sway, heave; 3-5 roll, pitch, yaw
    amplitude: jax.Array
    frequency: jax.Array
    ramp: float = eqx.field(static=True, default=0.0)
    phase: jax.Array = 0.0                                 # rad

    def coordinates(self, t):
        x = self.amplitude * jnp.sin(self.frequency * t + self.phase)
        if self.ramp > 0:
            x = x * smooth_ramp(t / self.ramp)
        return jnp.zeros(6).at[self.dof].set(x)

    def describe(self) -> tuple:
        phase = f" + {float(self.phase):g}" if float(self.phase) else ""
        ramp = f", faded in over {self.ramp:g} s" if self.ramp else ""
        return (("prescribed motion", f"{DOF_NAMES[self.dof]} = {float(self.amplitude):g} "
                                      f"sin({float(self.frequency):g} t{phase}){ramp}, other rigid dofs held"),)


class SpinUpMotion(AbstractPrescribedMotion):
    """One rotation whose rate grows smoothly to `rate` over `duration` (rate r(t / duration), the
    harmonic form's ramp), then stays: the Kane-Ryan-Banerjee hub; the others held at zero."""
    dof: int = eqx.field(static=True)      # 3-5 roll, pitch, yaw
    rate: float = eqx.field(static=True)   # final rate, rad/s
    duration: float = eqx.field(static=True)   # its time, s

    def coordinates(self, t):
        T, W = self.duration, self.rate
        c = T / (2.0 * jnp.pi)
        up = W / T * (0.5 * t * t + c * c * (jnp.cos(t / c) - 1.0))
        return jnp.zeros(6).at[self.dof].set(jnp.where(t < T, up, W * (0.5 * T) + W * (t - T)))

    def describe(self) -> tuple:
        return (("prescribed motion", f"{DOF_NAMES[self.dof]} rate spun up to {self.rate:g} rad/s over "
                                      f"{self.duration:g} s, other rigid dofs held"),)


class RecordedMotion(AbstractPrescribedMotion):
    """Coordinates from a record (`[vessel.forced] file`): a natural cubic spline through the samples
    of each recorded dof (value, slope and curvature continuous: the prescribed acceleration has no
    jump), zero for the dofs the record does not give. Piece i on [t_i, t_i+1] is
    ((c0 s + c1) s + c2) s + c3, s = t - t_i; found by a binary search, not a loop."""
    knots: jax.Array        # (n,) sample times, increasing
    coef: jax.Array         # (n - 1, 4, 6) the pieces' coefficients, highest power first
    about: About = eqx.field(static=True, default=About())     # the record's file and columns

    def coordinates(self, t):
        i = jnp.clip(jnp.searchsorted(self.knots, t, side="right") - 1, 0, self.knots.shape[0] - 2)
        s = t - self.knots[i]
        c = self.coef[i]
        return ((c[0] * s + c[1]) * s + c[2]) * s + c[3]

    def describe(self) -> tuple:
        return self.about.lines


def record_coefficients(times, columns, dofs):
    """(knots, coef) of `RecordedMotion` from a scene's record: `columns` ((dof name, samples), ...),
    `dofs` the six names in order. NumPy and SciPy, once per build."""
    from scipy.interpolate import CubicSpline
    t = np.asarray(times, dtype=float)
    coef = np.zeros((len(t) - 1, 4, 6))
    for name, values in columns:
        coef[:, :, dofs.index(name)] = CubicSpline(t, np.asarray(values, dtype=float), bc_type="natural").c.T
    return t, coef
