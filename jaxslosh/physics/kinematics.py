"""Floating-frame kinematics with Euler parameters (paper section 2).

Quaternions are scalar first, q = (q0, q1, q2, q3), |q| = 1. A(q) maps body-frame vectors to the
inertial frame (X = X0 + A (r + d), eq. 1). G(q) is the 3x4 matrix with omega = 2 G(q) q_dot
(body-frame angular velocity); G q = 0 and G G^T = I.

Rotations are advanced on the group (q_{n+1} = q_n * exp(Theta)), so |q| = 1 holds by construction;
the unit-norm constraint of eq. (25) needs no multiplier (docs/theory.md item 8).
"""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np


def mv3(A, x):
    """A @ x for A (k, 3): a product and a sum over the last axis, not a dot (a separate kernel
    launch, and the small-step loops are launch-bound); three operations where the three columns
    written out are eleven, each repeated by every jvp, vmap and transpose around it."""
    return jnp.sum(A * x, axis=-1)


def tv3(A, x):
    """A.T @ x for A (3, k), as mv3."""
    return jnp.sum(A * jnp.reshape(x, (3,) + (1,) * (jnp.ndim(A) - 1)), axis=0)


#: gather indices and signs of the cross-product matrix of v, read from (0, v0, v1, v2): one gather
#: and one product, where a nested jnp.array is some twenty operations, each repeated by every
#: jacfwd and vmap around it
_SKEW_INDEX = np.array([[0, 3, 2], [3, 0, 1], [2, 1, 0]])
_SKEW_SIGN = np.array([[0.0, -1.0, 1.0], [1.0, 0.0, -1.0], [-1.0, 1.0, 0.0]])
#: G(q) read from q the same way
_G_INDEX = np.array([[1, 0, 3, 2], [2, 3, 0, 1], [3, 2, 1, 0]])
_G_SIGN = np.array([[-1.0, 1.0, 1.0, -1.0], [-1.0, -1.0, 1.0, 1.0], [-1.0, 1.0, -1.0, 1.0]])


def skew(v):
    """The cross-product matrix: skew(a) @ b = a x b (the paper's tilde)."""
    v = jnp.asarray(v)
    return jnp.concatenate([jnp.zeros((1,), v.dtype), v])[_SKEW_INDEX] * _SKEW_SIGN


#: A(q) read from the outer product q q^T (entry 4 i + j: q_i q_j): each of A's nine entries is a
#: signed sum of four of its products (the off-diagonal factor 2 as the two symmetric entries)
_A_INDEX = np.array([[[0, 5, 10, 15], [6, 9, 3, 12], [7, 13, 2, 8]],
                     [[6, 9, 3, 12], [0, 5, 10, 15], [11, 14, 1, 4]],
                     [[7, 13, 2, 8], [11, 14, 1, 4], [0, 5, 10, 15]]])
_A_SIGN = np.array([[[1.0, 1.0, -1.0, -1.0], [1.0, 1.0, -1.0, -1.0], [1.0, 1.0, 1.0, 1.0]],
                    [[1.0, 1.0, 1.0, 1.0], [1.0, -1.0, 1.0, -1.0], [1.0, 1.0, -1.0, -1.0]],
                    [[1.0, 1.0, -1.0, -1.0], [1.0, 1.0, 1.0, 1.0], [1.0, -1.0, -1.0, 1.0]]])
_A_ROW, _A_COL = np.divmod(_A_INDEX, 4)


def rotation_matrix(q):
    """A(q): body to inertial, as one outer product, one gather and one signed sum: a few
    operations, where the nine entries written out are some sixty, each repeated by every jvp, vmap
    and transpose around it (the step linearises the residual for its preconditioner): written
    out, A was a third of the operations of the mast scene's step."""
    q = jnp.asarray(q)
    return jnp.sum(jnp.outer(q, q)[_A_ROW, _A_COL] * _A_SIGN, axis=-1)


def G_matrix(q):
    """G(q) with omega_body = 2 G q_dot (Nikravesh's L matrix)."""
    return jnp.asarray(q)[_G_INDEX] * _G_SIGN


#: the Hamilton product p q read from the outer product p q^T as rotation_matrix does
_QM_INDEX = np.array([[0, 5, 10, 15], [1, 4, 11, 14], [2, 7, 8, 13], [3, 6, 9, 12]])
_QM_SIGN = np.array([[1.0, -1.0, -1.0, -1.0], [1.0, 1.0, 1.0, -1.0], [1.0, -1.0, 1.0, 1.0], [1.0, 1.0, -1.0, 1.0]])
_QM_ROW, _QM_COL = np.divmod(_QM_INDEX, 4)


def quat_multiply(p, q):
    return jnp.sum(jnp.outer(p, q)[_QM_ROW, _QM_COL] * _QM_SIGN, axis=-1)


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
