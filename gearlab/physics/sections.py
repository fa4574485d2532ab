"""The generalised tooth section of thesis 2.2.5 (Table 2.2).

A tooth is a non-uniform cantilever along its centreline x (from the root circle, x = 0,
to the tip, x = d_h). Every fault of the thesis acts only on four arrays sampled along x:
the half thickness h_x, the area A_x, the second moment I_x and the effective face
width L(x). The stiffness engine integrates whatever these arrays hold, so a new fault
needs nothing but a function that edits them.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .geometry import Gear

DEFAULT_NODES = 2048


@dataclass(frozen=True)
class ToothSection:
    x: np.ndarray  # m, nodes from the root (0) to the tip (d_h); d_1 is always a node
    h: np.ndarray  # m, h_x: half thickness
    A: np.ndarray  # m^2, A_x
    I: np.ndarray  # m^4, I_x
    L: np.ndarray  # m, effective face width seen by the Hertzian contact
    d_1: float  # m, end of the straight root region (0 when the root circle lies above the base circle)
    face_width: float  # m, nominal L

    def replace(self, **arrays) -> ToothSection:
        return replace(self, **arrays)

    @property
    def tooth_height(self) -> float:
        return float(self.x[-1])

    def face_area_removed(self) -> float:
        """Area a fault takes from the face plane (L_nominal - L(x) integrated along x)."""
        return float(np.trapezoid(self.face_width - self.L, self.x))


def healthy_section(gear: Gear, face_width: float, nodes: int = DEFAULT_NODES) -> ToothSection:
    """Healthy tooth section of eq. 2.15-2.19 (case 1) or 2.30-2.32 (case 2)."""
    height = gear.tooth_height
    d_1 = gear.d_1
    # Nodes spaced about evenly along x, with d_1 exactly on a node so the straight root
    # region (constant h_x = R_b sin alpha_2) and the involute are integrated separately.
    n_root = max(2, round(nodes * d_1 / height)) if d_1 > 0 else 0
    n_inv = max(2, nodes - n_root)
    x_root = np.linspace(0.0, d_1, n_root, endpoint=False) if n_root else np.empty(0)
    x_inv = np.linspace(d_1, height, n_inv)
    # x(alpha) is monotone on the involute; invert it on a dense alpha grid.
    alpha = np.linspace(gear.alpha_root, gear.alpha_tip, 16 * n_inv)
    x_dense = gear.x_of(alpha)
    h_inv = np.interp(x_inv, x_dense, gear.half_thickness(alpha))  # x_dense increases with it
    h_inv[0] = gear.half_thickness(gear.alpha_root)
    x = np.concatenate([x_root, x_inv])
    h = np.concatenate([np.full(n_root, gear.R_b * np.sin(gear.alpha_2)), h_inv])
    L = np.full_like(x, face_width)
    return ToothSection(x=x, h=h, A=2 * h * L, I=2.0 / 3.0 * h**3 * L, L=L, d_1=d_1, face_width=face_width)
