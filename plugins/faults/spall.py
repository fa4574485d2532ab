"""Rectangular spall after Chaari et al. (2008) (2.2.3, eq. 2.73-2.75)."""

from __future__ import annotations

import numpy as np

from gearlab.api import (
    MM,
    Fault,
    GearlabInputError,
    healthy_section,
    hookimpl,
    parameters,
    region,
    scaled_ladder,
    setting,
)

# Tables 2.5 / 2.6: length, depth and start fixed, width growing.
LADDERS = {
    "luo2019": (
        {"l_s": 1e-3, "w_s": 0.0, "h_s": 1e-3, "x_1": 4e-3},
        {"l_s": 1e-3, "w_s": 15e-3, "h_s": 1e-3, "x_1": 4e-3},
    ),
    "meng2020": (
        {"l_s": 526e-6, "w_s": 0.0, "h_s": 1e-3, "x_1": 2.374e-3},
        {"l_s": 526e-6, "w_s": 19e-3, "h_s": 1e-3, "x_1": 2.374e-3},
    ),
}


class Spall(Fault):
    name = "spall"
    doc = "Rectangular spall of length l_s, width w_s and depth h_s starting x_1 from the root (Chaari 2008)."
    params = parameters(
        l_s=setting(float, 1e-3, low=0.0, high=0.05, **MM, doc="spall length along the profile"),
        w_s=setting(float, 0.0, low=0.0, high=1.0, **MM, doc="spall width across the face"),
        h_s=setting(float, 1e-3, low=0.0, high=0.05, **MM, doc="spall depth into the tooth"),
        x_1=setting(float, 4e-3, low=0.0, high=0.05, **MM, doc="start of the spall, measured from the tooth root"),
    )

    def check(self, params, pair, where):
        height = pair.pinion.tooth_height
        end = params["x_1"] + params["l_s"]
        if end > height:
            raise GearlabInputError(
                f"{where}: the spall ends {end * 1e3:g} mm from the root, past the tooth tip at {height * 1e3:.4g} mm "
                f"(x_1 + l_s must not exceed the tooth height)"
            )
        if params["w_s"] > pair.face_width:
            raise GearlabInputError(
                f"{where}: spall width w_s = {params['w_s'] * 1e3:g} mm "
                f"exceeds the face width {pair.face_width * 1e3:g} mm"
            )
        section = healthy_section(pair.pinion, pair.face_width)
        on = region(section, params["x_1"], end)
        if on.any() and params["h_s"] > section.h[on].min():
            raise GearlabInputError(
                f"{where}: spall depth h_s = {params['h_s'] * 1e3:g} mm is deeper than half the tooth there "
                f"({section.h[on].min() * 1e3:.3g} mm)"
            )

    def apply(self, section, params, pair):
        w, depth = params["w_s"], params["h_s"]
        if w <= 0 or params["l_s"] <= 0:
            return section
        on = region(section, params["x_1"], params["x_1"] + params["l_s"])
        L, A, I = section.L.copy(), section.A.copy(), section.I.copy()
        L[on] -= w  # eq. 2.73
        A[on] -= depth * w  # eq. 2.74
        I[on] -= w * depth**3 / 12  # eq. 2.75
        return section.replace(L=np.maximum(L, 0.0), A=np.maximum(A, 0.0), I=np.maximum(I, 0.0))

    def ladder_endpoints(self, pair):
        return scaled_ladder(pair, LADDERS, "meng2020")


@hookimpl
def gearlab_faults():
    return [Spall()]
