"""Tooth-tip corner broken off along a fracture line: a chip with a sharp edge (2.2.2 and 2.2.5).

The thesis's chip (Tian 2004, eq. 2.72) tapers: the width it takes grows hyperbolically from
nothing at depth b below the tip to c at the tip, so the chipped tooth pair stiffens and softens
smoothly and its contact is lost only at the very tip. A chip that breaks off leaves a fracture
surface instead: over the width c the tooth above the fracture line, depth b below the tip, is
gone. Where the contact point lies above that line the mating tooth touches only the width left,
L - c (no contact at all when c is the whole face width: the pair leaves mesh early, at the
line), and the section there keeps (L - c)/L of its area and second moment (the generalised
section of Table 2.2: A_x = 2 h_x L, I_x = 2 h_x^3 L / 3). The stiffness steps at the line
rather than sloping into it, so the chip's response is broadband where the tapered chip's is
not (docs/real_data.md, seventeenth round).
"""

from __future__ import annotations

import numpy as np

from gearlab.api import Fault, GearlabInputError, Param, hookimpl, scaled_ladder

# The chip's ladders (Tables 2.5 / 2.6): the same depth b, the width c growing to the full face.
LADDERS = {
    "luo2019": ({"b": 1e-3, "c": 0.0}, {"b": 1e-3, "c": 16e-3}),
    "meng2020": ({"b": 1.07e-3, "c": 0.0}, {"b": 1.07e-3, "c": 20e-3}),
}


class BrokenTip(Fault):
    name = "broken_tip"
    doc = "Tip corner broken off along a line b below the tip over width c: the chip with a sharp fracture edge."
    params = (
        Param("b", "m", 1e-3, 0.0, 0.05, "depth of the fracture line below the tooth tip", "mm"),
        Param("c", "m", 0.0, 0.0, 1.0, "width broken off across the face", "mm"),
    )

    def check(self, params, pair, where):
        height = pair.pinion.tooth_height
        if params["b"] >= height:
            raise GearlabInputError(
                f"{where}: fracture depth b = {params['b'] * 1e3:g} mm reaches past the tooth root "
                f"(tooth height {height * 1e3:.4g} mm)"
            )
        if params["c"] > pair.face_width:
            raise GearlabInputError(
                f"{where}: broken width c = {params['c'] * 1e3:g} mm exceeds "
                f"the face width {pair.face_width * 1e3:g} mm"
            )

    def apply(self, section, params, pair):
        b, c = params["b"], params["c"]
        if b <= 0 or c <= 0:
            return section
        above = section.x > section.tooth_height - b
        left = np.where(above, np.maximum(section.L - c, 0.0) / section.L, 1.0)  # share of the width left
        return section.replace(L=section.L * left, A=section.A * left, I=section.I * left)

    def ladder_endpoints(self, pair):
        return scaled_ladder(pair, LADDERS, "meng2020")


@hookimpl
def gearlab_faults():
    return [BrokenTip()]
