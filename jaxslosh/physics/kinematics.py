"""Floating-frame kinematics with Euler parameters (paper section 2).

Quaternions are scalar first, q = (q0, q1, q2, q3), |q| = 1. A(q) maps body-frame vectors to the
inertial frame (X = X0 + A (r + d), eq. 1). G(q) is the 3x4 matrix with omega = 2 G(q) q_dot
(body-frame angular velocity); G q = 0 and G G^T = I.

Rotations are advanced on the group (q_{n+1} = q_n * exp(Theta)), so |q| = 1 holds by construction;
the unit-norm constraint of eq. (25) needs no multiplier (PHYSICS.md section 2, item 8).
"""
from __future__ import annotations

import jax.numpy as jnp


def mv3(A, x):
    """A @ x for A (k, 3) as three scaled columns: elementwise, so XLA fuses it with its neighbours
    (a dot is a separate kernel launch, and the small-step loops are launch-bound)."""
    return A[..., 0] * x[0] + A[..., 1] * x[1] + A[..., 2] * x[2]


def tv3(A, x):
    """A.T @ x for A (3, k), as mv3."""
    return A[0] * x[0] + A[1] * x[1] + A[2] * x[2]


def skew(v):
    """The cross-product matrix: skew(a) @ b = a x b (the paper's tilde)."""
    return jnp.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rotation_matrix(q):
    """A(q): body to inertial."""
    q0, q1, q2, q3 = q
    return jnp.array([
        [q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3, 2 * (q1 * q2 - q0 * q3), 2 * (q1 * q3 + q0 * q2)],
        [2 * (q1 * q2 + q0 * q3), q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3, 2 * (q2 * q3 - q0 * q1)],
        [2 * (q1 * q3 - q0 * q2), 2 * (q2 * q3 + q0 * q1), q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3],
    ])


def G_matrix(q):
    """G(q) with omega_body = 2 G q_dot (Nikravesh's L matrix)."""
    q0, q1, q2, q3 = q
    return jnp.array([[-q1, q0, q3, -q2], [-q2, -q3, q0, q1], [-q3, q2, -q1, q0]])


def quat_multiply(p, q):
    p0, pv = p[0], p[1:]
    q0, qv = q[0], q[1:]
    return jnp.concatenate([jnp.array([p0 * q0 - pv @ qv]), p0 * qv + q0 * pv + jnp.cross(pv, qv)])


def quat_exp(theta):
    """Unit quaternion of the rotation vector theta (safe, and differentiable, at theta = 0)."""
    t2 = theta @ theta
    small = t2 < 1e-12
    t2s = jnp.where(small, 1.0, t2)
    t = jnp.sqrt(t2s)
    c = jnp.where(small, 1.0 - t2 / 8.0 + t2 * t2 / 384.0, jnp.cos(0.5 * t))
    s = jnp.where(small, 0.5 - t2 / 48.0 + t2 * t2 / 3840.0, jnp.sin(0.5 * t) / t)
    return jnp.concatenate([jnp.array([c]), s * theta])


def quat_from_rpy(rpy):
    """Quaternion of roll-pitch-yaw angles (Z-Y-X convention: A = Rz(yaw) Ry(pitch) Rx(roll))."""
    r, p, y = 0.5 * rpy[0], 0.5 * rpy[1], 0.5 * rpy[2]
    cr, sr, cp, sp, cy, sy = jnp.cos(r), jnp.sin(r), jnp.cos(p), jnp.sin(p), jnp.cos(y), jnp.sin(y)
    return jnp.array([
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ])


def rpy_from_quat(q):
    """Roll, pitch, yaw (Z-Y-X) of a unit quaternion."""
    q0, q1, q2, q3 = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    roll = jnp.arctan2(2 * (q0 * q1 + q2 * q3), 1 - 2 * (q1 * q1 + q2 * q2))
    pitch = jnp.arcsin(jnp.clip(2 * (q0 * q2 - q3 * q1), -1.0, 1.0))
    yaw = jnp.arctan2(2 * (q0 * q3 + q1 * q2), 1 - 2 * (q2 * q2 + q3 * q3))
    return jnp.stack([roll, pitch, yaw], axis=-1)


def spin_tensor_components(omega):
    """The six components (xx, yy, zz, yz, xz, xy) of W = omega omega^T, in the order of
    fem.structure.centrifugal_stiffness's matrices (jax or numpy)."""
    w = omega
    return [w[0] * w[0], w[1] * w[1], w[2] * w[2], w[1] * w[2], w[0] * w[2], w[0] * w[1]]
