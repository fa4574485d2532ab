"""Surface pits after Meng et al. (2021) with the thesis's Gaussian sampling (2.2.4).

N spheres are drawn once from a seeded generator (centre u, radius r, contact angle theta);
intensity `count` uses the first `count` of them, so every intensity contains the pits of
the milder ones (thesis 2.4.3.1).
"""

from __future__ import annotations

import math

import numpy as np

from gearlab.api import DEG, MM, UM, Fault, GearlabInputError, hookimpl, parameters, scaled_ladder, setting

_PIT_SHAPE = {"r": 80e-6, "sigma_r": 0.0, "theta": math.radians(30), "sigma_theta": 0.0, "n_total": 2000, "seed": 0}
# Tables 2.5 / 2.6: pit shape and pitting line fixed, the number of pits growing to 2000.
LADDERS = {
    "luo2019": (
        {**_PIT_SHAPE, "u": 4.387e-3, "sigma_u": 296e-6, "count": 0},
        {**_PIT_SHAPE, "u": 4.387e-3, "sigma_u": 296e-6, "count": 2000},
    ),
    "meng2020": (
        {**_PIT_SHAPE, "u": 2.5e-3, "sigma_u": 210.4e-6, "count": 0},
        {**_PIT_SHAPE, "u": 2.5e-3, "sigma_u": 210.4e-6, "count": 2000},
    ),
}


def draw_pits(params) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The first `count` of one seeded draw of `n_total` pits: centres u, radii r, angles theta."""
    n = params["n_total"]
    rng = np.random.default_rng(params["seed"])
    u = rng.normal(params["u"], params["sigma_u"], n)  # eq. 2.76
    r = rng.normal(params["r"], params["sigma_r"], n)  # eq. 2.77
    theta = rng.normal(params["theta"], params["sigma_theta"], n)  # eq. 2.78
    k = params["count"]
    # A normal draw can fall outside what a pit can be: no negative radii, angles in (0, 90 deg].
    return u[:k], np.maximum(r[:k], 0.0), np.clip(theta[:k], 1e-6, math.pi / 2)


class Pit(Fault):
    name = "pit"
    doc = "Distributed spherical pits (Meng et al. 2021), Gaussian location and shape, first `count` of N."
    params = parameters(
        count=setting(int, 0, low=0, high=100000, doc="number of pits on the tooth (the first of the seeded draw)"),
        n_total=setting(int, 2000, low=1, high=100000, doc="size of the seeded draw the pits are taken from"),
        u=setting(float, 4.387e-3, low=0.0, high=0.05, **MM, doc="mean pitting line, from the tooth root"),
        sigma_u=setting(float, 296e-6, low=0.0, high=0.05, **UM, doc="standard deviation of the pit centres"),
        r=setting(float, 80e-6, low=0.0, high=0.005, **UM, doc="mean sphere radius"),
        sigma_r=setting(float, 0.0, low=0.0, high=0.005, **UM, doc="standard deviation of the radius"),
        theta=setting(
            float, math.radians(30), low=math.radians(0.1), high=math.pi / 2, **DEG, doc="mean contact angle"
        ),
        sigma_theta=setting(
            float, 0.0, low=0.0, high=math.pi / 2, **DEG, doc="standard deviation of the contact angle"
        ),
        seed=setting(int, 0, low=0, high=2**32 - 1, doc="seed of the pit draw"),
    )

    def check(self, params, pair, where):
        if params["count"] > params["n_total"]:
            raise GearlabInputError(
                f"{where}: count = {params['count']} pits exceeds the draw size n_total = {params['n_total']}"
            )
        height = pair.pinion.tooth_height
        if params["u"] > height:
            raise GearlabInputError(
                f"{where}: pitting line u = {params['u'] * 1e3:g} mm lies past the tooth tip ({height * 1e3:.4g} mm)"
            )

    def apply(self, section, params, pair):
        u, r, theta = draw_pits(params)
        if len(u) == 0:
            return section
        x = section.x
        r_sfc = r * np.sin(theta)  # eq. 2.84: bounds from the surface circle (the thesis's correction)
        lo = np.searchsorted(x, u - r_sfc, side="left")
        hi = np.searchsorted(x, u + r_sfc, side="right")
        counts = hi - lo
        node = np.repeat(lo, counts) + np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        pit = np.repeat(np.arange(len(u)), counts)
        du = u[pit] - x[node]
        rp, th, rs = r[pit], theta[pit], r_sfc[pit]
        dL = 2 * np.sqrt(np.maximum(rs**2 - du**2, 0.0))  # eq. 2.80
        dR = np.sqrt(np.maximum(rp**2 - du**2, 0.0))  # eq. 2.81
        seg = 2 * th - np.sin(2 * th)
        dA = dR**2 * seg / 2  # eq. 2.82
        A, h = section.A[node], section.h[node]
        centroid = 4 * dR * np.sin(th) ** 3 / (3 * seg) - dR * np.cos(th)  # from the tooth surface, inwards
        dI = dR**4 / 72 * (18 * th - 9 * np.sin(2 * th) * np.cos(2 * th) - 64 * np.sin(th) ** 6 / seg) + (
            A * dA * (h - centroid) ** 2 / np.maximum(A - dA, 1e-30)
        )  # eq. 2.83
        n = len(x)
        total = lambda w: np.bincount(node, weights=w, minlength=n)  # noqa: E731
        return section.replace(  # eq. 2.85-2.87; a tooth cannot lose more than it has
            L=np.maximum(section.L - total(dL), 0.0),
            A=np.maximum(section.A - total(dA), 0.0),
            I=np.maximum(section.I - total(dI), 0.0),
        )

    def ladder_endpoints(self, pair):
        return scaled_ladder(pair, LADDERS, "meng2020")


@hookimpl
def gearlab_faults():
    return [Pit()]
