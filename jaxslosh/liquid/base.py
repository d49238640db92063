"""The liquid's contract (`AbstractLiquid`: what the solver, the build, the frames and `check` ask
of every liquid model) and the terms that act on the deformable block besides its own.

The models are the sub-packages of jaxslosh/liquid: nodal/ (the stabilized and paper elements),
face/ (the face-normal "rt" element), modal/ (reduced to modes), multimodal/; NoLiquid without tanks.
The nodal liquid's kinematics (liquid/nodal/term.py) show the form every full-order one takes:

The liquid's displacement d is relative to the tank, on the dofs the slip walls leave free. Its
particle kinematics keep d in the rotational terms (eqs. 1-4), so the coupled system is Lagrangian:

    T = 1/2 sum_ij Ms_ij v_i.v_j,   v_i = A^T V0 + d_dot_i + omega x (r_i + d_i)     (body components)
    V = 1/2 d^T K d - g_b.(sum_i m_i d_i)

with g_b gravity in the body frame (turning with the body: the load of eq. 32). The frozen liquid's
own weight and moment are balanced with the hull's by the displaced water (hydrostatics), or are the
vessel's Weight term; docs/theory.md item 9: GM_T and GM_L are for the frozen liquid, so only d adds a
gravity moment here.
"""
from __future__ import annotations

import abc
import dataclasses
from typing import Any, NamedTuple, Optional
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..fem.linalg import inv
from ..physics.about import About
from ..physics.kinematics import mv3, quat_multiply, skew, spin_tensor_components, tv3
from ..physics.terms import AbstractTerm, Config, Kin, Rows
from ..staging import staged
from .words import TankWords


def nodal_product(Ms, a):
    """Ms @ a for a nodal field a (N, 3): three matrix-vector products. XLA's CPU product of a dense
    (N, N) by an (N, 3) takes a general matrix-product path that costs about twice the three
    products (benchmarks/speed/floor.py: the paper example's residual evaluates it at every Newton
    iteration). The sparse paths' matrices (liquid/nodal/sparse.HostSparse) keep their own product."""
    if not isinstance(Ms, (jax.Array, np.ndarray)) or a.ndim != 2:
        return Ms @ a
    return jnp.stack([Ms @ a[:, i] for i in range(a.shape[1])], axis=1)


def point_mass_scale(m, x, total=None):
    """The rigid rows' scales of point masses m (n,) at x (n, 3), body frame: their total mass for
    the translations and their moments of inertia about the body axes for the rotations."""
    I = jnp.array([m @ (x[:, 1] ** 2 + x[:, 2] ** 2), m @ (x[:, 0] ** 2 + x[:, 2] ** 2),
                   m @ (x[:, 0] ** 2 + x[:, 1] ** 2)])
    return jnp.concatenate([jnp.full(3, m.sum() if total is None else total), I])

def particle_rows(liquid, k: Kin, field, m, inertia) -> Rows:
    """Eq. (4) for a full-order liquid of particles at `liquid.r` (body frame) with masses m (n,) and
    displacements field(d) (n, 3) (the nodal liquid's nodes, the face-normal one's Gauss points): the
    particle accelerations (body components), their inertia forces inertia(a), what they do on the
    rigid rows and on the liquid's own (`liquid.free_part`); the stiffness `liquid.K` and the gravity
    load."""
    c, A, omega = k.c, k.A, k.omega
    a0, alpha = k.a6[:3], k.a6[3:6]
    D, Dv, Da = field(c.d), field(k.d_dot), field(k.d_acc)
    x = liquid.r + D
    a = tv3(A, a0) + Da + jnp.cross(alpha, x)
    if liquid.coriolis:
        a = a + 2.0 * jnp.cross(omega, Dv)
    if liquid.centrifugal:
        a = a + jnp.cross(omega, jnp.cross(omega, x))
    F = inertia(a)
    mD = m @ D                                                  # first moment of d
    r_t = mv3(A, F.sum(axis=0))
    r_r = jnp.cross(x, F).sum(axis=0) - jnp.cross(mD, k.g_b)
    r_d = liquid.free_part(F - m[:, None] * k.g_b) + liquid.K @ c.d
    return Rows(jnp.concatenate([r_t, r_r]), r_d)


class StepInverse(NamedTuple):
    """The inverses of a liquid's constant Newton blocks (solve/linear.make_solver): each a matrix or
    an operator with `@`."""
    step: Any                 # (c_a M_ff + K_ff)^-1
    mass: Any                 # M_ff^-1 (the initial accelerations)
    sub: Optional[Any]        # the step block's at a sub-step's c_a (None without sub-steps)
    stiffness_rows: Any       # (nf,) sum_j |K_ij|: the round-off floor of the rows (Solver.noise)


@staged
def _abs_rowsum(K):
    return jnp.sum(jnp.abs(jnp.asarray(K)), axis=1)


def dense_step_inverse(liquid, c_a, c_a_sub=None) -> StepInverse:
    """The inverses of a liquid's constant blocks for the Newton step at c_a (and a sub-step's
    c_a_sub), dense, from its `constant_blocks` (NumPy for concrete matrices, JAX when the liquid
    was built from traced values): every model's `step_inverse` but on large meshes, where the nodal
    and face-normal ones use their own solves. They only precondition the Newton iterations and the
    tangent solves, so they are formed from `stop_gradient` values."""
    M_ff, K_ff = jax.lax.stop_gradient(liquid).constant_blocks()
    traced = isinstance(M_ff, jax.core.Tracer) or isinstance(K_ff, jax.core.Tracer)
    if not traced:
        M_ff, K_ff = np.asarray(M_ff), np.asarray(K_ff)

    def inverse(A):
        return inv(A) if traced else jnp.asarray(np.linalg.inv(A))

    def step(c):
        Cs = c * M_ff + K_ff
        return inverse(0.5 * (Cs + Cs.T))

    return StepInverse(step(c_a), inverse(M_ff), step(c_a_sub) if c_a_sub is not None else None,
                       _abs_rowsum(K_ff))


class AbstractLiquid(AbstractTerm):
    """The owner of the deformable unknowns d: what the solver, the build, the frames and `check`
    need of it besides its rows and energies. Every model is a final subclass (equinox's
    abstract-or-final); code outside jaxslosh/liquid asks these, never which class it holds."""
    #: its rows are nonlinear in d (liquid/multimodal/term.py): Newton linearises its few unknowns with the
    #: rigid ones instead of using a constant block (solve/linear.py)
    nonlinear = False
    #: no tank liquid and nothing else in the vessel's frame (NoLiquid)
    empty = False
    #: its static start `static_start` can be traced whole (False: host solves, the sparse nodal block's)
    staged_start = True

    @abc.abstractmethod
    def total_mass(self):
        """The liquid's mass (with elastic walls and vessel-frame structures: theirs too), kg."""

    @abc.abstractmethod
    def static_start(self, g_b):
        """d0 of the discrete hydrostatic equilibrium K d0 = F_g under the body gravity g_b
        (docs/theory.md item 6), so that the stiff acoustic modes are not excited by the start."""

    @abc.abstractmethod
    def constant_blocks(self):
        """(M_ff, K_ff): its constant mass and stiffness on the unknowns, dense."""

    @abc.abstractmethod
    def step_inverse(self, c_a, c_a_sub=None) -> StepInverse:
        """The inverses of its constant blocks for the Newton step at c_a (and a sub-step's c_a_sub):
        `dense_step_inverse` above, or a model's own solves on large meshes. They only precondition
        the Newton iterations and the tangent solves (solve/linear.make_solver asks this alone)."""

    @abc.abstractmethod
    def describe(self) -> tuple:
        """(effect, text) lines: what this liquid adds to the model, as `jaxslosh check` lists it."""

    @abc.abstractmethod
    def with_effects(self, coriolis: bool, centrifugal: bool, about: About) -> "AbstractLiquid":
        """The liquid with the scene's `[effects]` switches of its inertial loads (where the model
        has such switches) and its tanks' lines `about` (assemble/about.py liquid_about)."""

    # What a model answers of one tank before any block is built, asked of the class that runs the
    # tank's form (liquid/forms.py `tank_liquid`): `jaxslosh modes`, `check` and the cost estimate.
    @classmethod
    @abc.abstractmethod
    def tank_unknowns(cls, tank) -> int:
        """The tank's free unknowns at full order in this model, counted from its keys (a reduced
        tank's are its element's: the modes are cut from them)."""

    @classmethod
    @abc.abstractmethod
    def sloshing_modes(cls, tank, g: float, n: int = 10):
        """The n lowest natural modes of the tank's liquid (with its elastic walls, where it has them)
        at gravity g, the vessel held fixed: `liquid/modes.Modes` (or `liquid/walls.TankModes`)."""

    @classmethod
    @abc.abstractmethod
    def tank_bytes(cls, tank, sparse: bool, host_lu: bool = False, rt_dense: bool = False) -> float:
        """The memory the tank's liquid takes at its largest phase, an estimate (liquid/cost.py the
        shared pieces): on the sparse way or not (`sparse`), the host's sparse LU (`host_lu`) or
        `simulation.linear_solver = "dense"` (`rt_dense`)."""

    # The tank's liquid in `jaxslosh check`'s words and the run's validity watch (assemble/about.py,
    # effects.py, run/validity.py ask these of `tank_liquid(tank)`; liquid/words.py the shared pieces).
    @classmethod
    @abc.abstractmethod
    def describe_tank(cls, tank) -> TankWords:
        """The tank's liquid in words (liquid/words.py TankWords): its line in the liquid term, its
        elastic walls' lines, its mesh (or modes), what its damping damps and the model's name."""

    @classmethod
    @abc.abstractmethod
    def surface_table(cls, tank, g: float):
        """What the run's validity watch reads of a tank's modal free surface (its slope, crest index and
        round-off floor: liquid/multimodal/watch.py SurfaceTable), or None for a model without one."""

    @property
    @abc.abstractmethod
    def nf(self) -> int:
        """Its unknowns."""

    @abc.abstractmethod
    def d_scale(self):
        """(nf,) a mass per row, so that a row over it is an acceleration."""

    # The hooks below have a neutral answer for most models; each final class still states its own
    # (equinox's abstract-or-final: no default to inherit by accident).
    @abc.abstractmethod
    def roundoff(self, d):
        """The round-off floor of its scaled rows at d beyond the solver's own (solve/linear.Solver.noise),
        which the Newton iterations aim at when it is above the tolerance: zero for a linear liquid."""

    @abc.abstractmethod
    def frame_field(self, d):
        """What a saved frame keeps of d (the nodal field, or modal coordinates)."""

    @abc.abstractmethod
    def nodal_fields(self, D):
        """Frames' kept fields (..., k) or (..., N, 3) -> nodal displacement fields (..., N, 3)."""

    @abc.abstractmethod
    def probe_displacements(self, weights, modal, d):
        """(P, 3) displacement of the probes (interpolation `weights` (P, N), or `modal` (P, m, 3))."""

    @abc.abstractmethod
    def surface_heave(self, d, nodes):
        """The vertical displacement (k,) of the points `nodes` of its free surface (a tank's, as the
        block's `surfaces` lists them): the run's validity watch."""

    @abc.abstractmethod
    def probe_modal(self, weights):
        """The probes' weights on the modal coordinates (P, m, 3) from their nodal interpolation
        `weights` (P, N), for a liquid whose d is modal; None where the probes read the nodal field
        (or where the model's builder makes them from the scene: liquid/block.py `probe_rows`)."""

    @abc.abstractmethod
    def rigid_first_moment(self):
        """sum_i m_i r_i (3,) of the undeformed block about the frame origin, kg m."""

    @abc.abstractmethod
    def for_batch(self) -> "AbstractLiquid":
        """The same liquid in the form a vmapped batch of runs computes fastest (most: itself)."""


def switch_inertial(liquid, coriolis: bool, centrifugal: bool, about: About):
    """A nodal, face-normal or reduced liquid's `with_effects`: its Coriolis and centrifugal loads
    switched as `[effects]` says, and its lines."""
    return dataclasses.replace(liquid, coriolis=coriolis, centrifugal=centrifugal, about=about)


def inertial_lines(liquid) -> tuple:
    """A nodal, face-normal or reduced liquid's lines: its tanks' (its `about`, set at assembly),
    then the inertial loads its `coriolis` and `centrifugal` switches keep."""
    lines = liquid.about.lines
    if liquid.coriolis:
        lines += (("Coriolis", "2 omega x d_dot on the liquid (eq. 19)"),)
    if liquid.centrifugal:
        lines += (("centrifugal", "omega x (omega x r) on the liquid (eq. 19)"),)
    return lines


class NoLiquid(AbstractLiquid):
    """A vessel without tank liquid: no unknowns, no rows."""
    empty = True
    nf = 0
    n_nodes = 0
    sparse = False

    def rows(self, k: Kin) -> Rows:
        return Rows(jnp.zeros(6), jnp.zeros(0))

    def d_scale(self):
        return jnp.zeros(0)

    def frame_field(self, d):
        return jnp.zeros((0, 3))

    def nodal_fields(self, D):
        return D

    def probe_displacements(self, weights, modal, d):
        return jnp.zeros((weights.shape[0], 3))

    def total_mass(self):
        return jnp.zeros(())

    def static_start(self, g_b):
        return jnp.zeros(0)

    def constant_blocks(self):
        return jnp.zeros((0, 0)), jnp.zeros((0, 0))

    def step_inverse(self, c_a, c_a_sub=None) -> StepInverse:
        return dense_step_inverse(self, c_a, c_a_sub)

    def describe(self) -> tuple:
        return ()

    def with_effects(self, coriolis: bool, centrifugal: bool, about: About) -> "NoLiquid":
        return self           # nothing to switch, nothing to list

    def roundoff(self, d):
        return jnp.zeros(())

    def surface_heave(self, d, nodes):
        return jnp.zeros(jnp.shape(nodes))

    def probe_modal(self, weights):
        return None

    def rigid_first_moment(self):
        return jnp.zeros(3)

    def for_batch(self) -> "NoLiquid":
        return self

    @classmethod
    def tank_unknowns(cls, tank) -> int:
        return 0

    @classmethod
    def sloshing_modes(cls, tank, g: float, n: int = 10):
        raise ValueError("a vessel without tank liquid has no sloshing modes")

    @classmethod
    def tank_bytes(cls, tank, sparse: bool, host_lu: bool = False, rt_dense: bool = False) -> float:
        return 0.0

    # no tank runs NoLiquid (liquid/forms.py tank_liquid): never asked of a tank
    @classmethod
    def describe_tank(cls, tank) -> TankWords:
        raise ValueError("a vessel without tank liquid has no tank to describe")

    @classmethod
    def surface_table(cls, tank, g: float):
        return None


class RotationPenalty(AbstractTerm):
    """The stabilized liquid element's penalty on the absolute rotation curl d + 2 theta (docs/theory.md
    item 5): d^T K_dt theta + 1/2 theta^T K_tt theta (its d-d block is in the liquid's K), with theta
    the small rotation of the body since the attitude at which the liquid is irrotational (the start).
    Rows by JAX from this potential."""
    Kdt: jax.Array        # (nf, 3)
    Ktt: jax.Array        # (3, 3)
    q_ref: jax.Array      # (4,)

    def describe(self) -> tuple:
        return (("rotation penalty", "the liquid's absolute rotation held at zero (docs/theory.md item 5): "
                                     "no spurious rotational modes of the element"),)

    def rotation(self, q):
        """theta = 2 vec(q_ref^-1 q): the small rotation since the reference attitude (body frame),
        and its derivative along body-frame rotation increments, d theta / d eps."""
        dq = quat_multiply(jnp.concatenate([self.q_ref[:1], -self.q_ref[1:]]), q)
        sgn = jnp.where(dq[0] < 0, -1.0, 1.0)
        return 2.0 * sgn * dq[1:], sgn * (dq[0] * jnp.eye(3) + skew(dq[1:]))

    def energy(self, c: Config):
        th, _ = self.rotation(c.q)
        return c.d @ (self.Kdt @ th) + 0.5 * th @ (self.Ktt @ th)

    def rows(self, k: Kin) -> Rows:
        """The gradient of `energy` along the increments, written out (tests/physics/test_model.py checks it
        with the liquid's: the whole residual against the gradient of the potential)."""
        th, J = self.rotation(k.c.q)
        d = k.c.d
        return Rows(jnp.concatenate([jnp.zeros(3), tv3(J, self.Kdt.T @ d + mv3(self.Ktt, th))]), mv3(self.Kdt, th))

    def potential(self, k: Kin):
        return self.energy(k.c)


def rotation_penalty(terms) -> Optional["RotationPenalty"]:
    """The liquid's rotation penalty among a system's `terms` (None without: no liquid, the "paper"
    element), for the analyses that split the potential energy by its parts."""
    return next((t for t in terms if isinstance(t, RotationPenalty)), None)


class SpinStiffening(AbstractTerm):
    """Structures in the vessel's frame with centrifugal stiffening: the geometric stiffness of the
    stress the spin causes, K_G(omega) = sum_k (omega omega^T)_k K_k (fem/structure.py). It follows
    the current spin, so it has no potential of its own. The structures' unknowns are the block's
    last ones, from `offset` on (the liquid's come first)."""
    Kg: jax.Array         # (6, n, n) on the unknowns offset ... offset + n
    about: About = eqx.field(static=True, default=About())     # the stiffened structures
    offset: int = eqx.field(static=True, default=0)

    def rows(self, k: Kin) -> Rows:
        W = jnp.stack(spin_tensor_components(k.omega))
        d = k.c.d
        n = self.Kg.shape[1]
        f = jnp.einsum("k,kij,j->i", W, self.Kg, d[self.offset:self.offset + n])
        return Rows(jnp.zeros(6), jnp.concatenate([jnp.zeros(self.offset, d.dtype), f,
                                                   jnp.zeros(d.shape[0] - self.offset - n, d.dtype)]))

    def describe(self) -> tuple:
        return self.about.lines
