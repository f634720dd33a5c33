"""Small helpers shared by the URDF generators: number formatting, rotations, inertia sums."""

from __future__ import annotations

import math

import numpy as np

from tools.fitting import orthonormal_basis


def rpy_to_matrix(rpy) -> np.ndarray:
    """URDF fixed-axis roll-pitch-yaw: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = (float(v) for v in rpy)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def matrix_to_rpy(R: np.ndarray) -> np.ndarray:
    """Inverse of :func:`rpy_to_matrix` (pitch in [-pi/2, pi/2])."""
    R = np.asarray(R, float)
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if abs(math.cos(pitch)) < 1e-10:  # gimbal lock: put everything in yaw
        roll = 0.0
        yaw = math.atan2(-R[0, 1], R[1, 1])
    else:
        roll = math.atan2(R[2, 1], R[2, 2])
        yaw = math.atan2(R[1, 0], R[0, 0])
    return np.array([roll, pitch, yaw])


def rotation_z_to(axis: np.ndarray) -> np.ndarray:
    """A rotation whose z column is ``axis`` (deterministic)."""
    z = axis / np.linalg.norm(axis)
    u, v = orthonormal_basis(z)
    R = np.column_stack([u, v, z])
    if np.linalg.det(R) < 0:
        R[:, 0] *= -1
    return R


def combine_inertias(parts: list[tuple[float, np.ndarray, np.ndarray]]) -> tuple[float, np.ndarray, np.ndarray]:
    m = sum(p[0] for p in parts)
    com = sum(p[0] * np.asarray(p[1]) for p in parts) / m
    inertia = np.zeros((3, 3))
    for mi, ci, Ii in parts:
        d = np.asarray(ci) - com
        inertia += Ii + mi * (np.dot(d, d) * np.eye(3) - np.outer(d, d))
    return m, com, inertia


def fmt(x: float) -> str:
    x = float(x)
    if abs(x) < 1e-12:
        x = 0.0
    return f"{x:.10g}"


def vec(v) -> str:
    return " ".join(fmt(x) for x in v)


def origin_xml(X: np.ndarray) -> str:
    return f'<origin xyz="{vec(X[:3, 3])}" rpy="{vec(matrix_to_rpy(X[:3, :3]))}"/>'
