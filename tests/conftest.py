"""Shared builders for the tests."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")   # the tests write figures to files only (the library never picks a backend)

import csjm_opt as co

#: Table 3's original pose R0 with errata item 3 applied (element (3,2) = -0.300).
R0_CORRECTED = np.array([[0.992, -0.060, -0.111],
                         [0.090, 0.952, 0.292],
                         [0.088, -0.300, 0.950]])
#: Table 3's pre-load (total load on the platform, N m, in {A}).
TAU0_TABLE3 = np.array([-0.06, -3.08, 1.07])


@pytest.fixture(scope="session")
def rig() -> co.Rig:
    return co.paper_rig()


@pytest.fixture(scope="session")
def model(rig) -> co.Model:
    return co.Model(rig)


def cable_energy(rig: co.Rig, R: np.ndarray, rest_lengths: np.ndarray) -> float:
    """Phi = sum 1/2 k (c - l)^2 over taut cables, written from scratch (no package code)."""
    A = np.asarray(rig.platform_holes_A_m)
    B = np.asarray(rig.base_holes_B_m)
    c = np.linalg.norm(B - A @ R.T, axis=1)
    stretch = np.maximum(c - rest_lengths, 0.0)
    return float(0.5 * np.sum(rig.cable_stiffness_N_per_m * stretch**2))


def rodrigues(w: np.ndarray) -> np.ndarray:
    """exp(hat(w)) written from scratch for the tests (w not tiny)."""
    th = np.linalg.norm(w)
    if th < 1e-12:
        return np.eye(3)
    k = w / th
    Kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * Kx + (1 - np.cos(th)) * Kx @ Kx


def fd_hessian(f, h: float = 1e-4) -> np.ndarray:
    """Central finite-difference Hessian of f(zeta) at zeta = 0 (3x3, symmetric by construction)."""
    E = np.eye(3)
    H = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            H[i, j] = (f(h * E[i] + h * E[j]) - f(h * E[i] - h * E[j])
                       - f(-h * E[i] + h * E[j]) + f(-h * E[i] - h * E[j])) / (4 * h * h)
    return H


def fd_gradient(f, h: float = 1e-6) -> np.ndarray:
    E = np.eye(3)
    return np.array([(f(h * E[i]) - f(-h * E[i])) / (2 * h) for i in range(3)])
