"""Tooth-tip corner broken off along a fracture line: a chip with a sharp edge (2.2.2 and 2.2.5).

The thesis's chip (Tian 2004, eq. 2.72) tapers: the width it takes grows hyperbolically from
nothing at depth b below the tip to c at the tip, so the chipped tooth pair stiffens and softens
smoothly and its contact is lost only at the very tip. A chip that breaks off leaves a fracture
surface instead: over the width c the tooth above the fracture line, depth b below the tip, is
gone. Where the contact point lies above that line the mating tooth touches only the width left,
L - c (no contact at all when c is the whole face width: the pair leaves mesh early, at the
line), and the section there keeps (L - c)/L of its area and second moment (the generalised
section of Table 2.2: A_x = 2 h_x L, I_x = 2 h_x^3 L / 3). The same parameters, limits and
ladder as the chip (b fixed, c growing to the full face), so step n of either is the same b and
c; only the shape of the loss differs (docs/real_data.md, "What limits it").
"""

from __future__ import annotations

import numpy as np

from gearlab.api import hookimpl
from gearlab_plugins.faults.chip import Chip


class BrokenTip(Chip):
    name = "broken_tip"
    doc = "Tip corner broken off along a line b below the tip over width c: the chip with a sharp fracture edge."

    def apply(self, section, params, pair):
        b, c = params["b"], params["c"]
        if b <= 0 or c <= 0:
            return section
        above = section.x > section.tooth_height - b
        left = np.where(above, np.maximum(section.L - c, 0.0) / section.L, 1.0)  # share of the width left
        return section.replace(L=section.L * left, A=section.A * left, I=section.I * left)


@hookimpl
def gearlab_faults():
    return [BrokenTip()]
