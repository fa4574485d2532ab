"""Tooth-tip chip after Tian (2004): a hyperbolic loss of face width at the tip (2.2.2).

Only the effective width L(x) changes, so only the Hertzian term is affected.
"""

from __future__ import annotations

import numpy as np

from gearlab.api import MM, Fault, GearlabInputError, hookimpl, parameters, scaled_ladder, setting

# Tables 2.5 / 2.6: chip depth b fixed, width c growing to the full face width.
LADDERS = {
    "luo2019": ({"b": 1e-3, "c": 0.0}, {"b": 1e-3, "c": 16e-3}),
    "meng2020": ({"b": 1.07e-3, "c": 0.0}, {"b": 1.07e-3, "c": 20e-3}),
}


class Chip(Fault):
    name = "chip"
    doc = "Corner chip at the tooth tip (Tian 2004): face width lost over the top b of the tooth."
    params = parameters(
        b=setting(float, 1e-3, low=0.0, high=0.05, **MM, doc="chip depth down the tooth face from the tip"),
        c=setting(float, 0.0, low=0.0, high=1.0, **MM, doc="chip width across the face at the tip"),
    )

    def check(self, params, pair, where):
        height = pair.pinion.tooth_height
        if params["b"] >= height:
            raise GearlabInputError(
                f"{where}: chip depth b = {params['b'] * 1e3:g} mm reaches past the tooth root "
                f"(tooth height {height * 1e3:.4g} mm)"
            )
        if params["c"] > pair.face_width:
            raise GearlabInputError(
                f"{where}: chip width c = {params['c'] * 1e3:g} mm exceeds the face width {pair.face_width * 1e3:g} mm"
            )

    def apply(self, section, params, pair):
        b, c = params["b"], params["c"]
        if b <= 0 or c <= 0:
            return section
        d_h, x = section.tooth_height, section.x
        on_chip = x >= d_h - b
        loss = np.zeros_like(x)
        xc = x[on_chip]
        loss[on_chip] = d_h * c / b - (d_h**2 * c / b - d_h * c) / xc  # eq. 2.72
        return section.replace(L=np.maximum(section.L - loss, 0.0))

    def ladder_endpoints(self, pair):
        return scaled_ladder(pair, LADDERS, "meng2020")


@hookimpl
def gearlab_faults():
    return [Chip()]
