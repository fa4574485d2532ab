"""Uniform flank wear: a fault type added from outside gearlab (thesis 2.2.5, Table 2.2).

Geometry
--------
Wear removes a layer of uniform depth delta (``depth``, measured normal to the flank) from
the loaded flank, across the whole face width, over a band of the tooth height. Positions
along the tooth are fractions of the tooth height d_h, measured from the root circle
along the tooth centreline x (0 = root, 1 = tip), so the same values suit any gear pair:

    band:  band_start * d_h  <=  x  <=  band_end * d_h

Only the loaded flank wears (the gearbox runs one way), so on the band the tooth is
2 h_x - delta thick instead of 2 h_x. As the crack model does (eq. 2.67, which keeps the
material between the crack and the far flank), the worn strip is replaced by the
symmetric strip of the same thickness:

    h_x,wear = h_x - delta / 2
    A_x,wear = 2 h_x,wear L             (the form of eq. 2.68)
    I_x,wear = (2/3) h_x,wear^3 L       (the form of eq. 2.69)

which is exact for the area and for the second moment of the worn strip about its own
centre. L(x) does not change (the contact line still spans the face), so the Hertzian
term is untouched; like spall and pit, the contact points and load angle stay those of
the unworn involute.

Row for Table 2.2:  wear | depth, band_start, band_end | h_x, A_x, I_x | this module.
"""

from __future__ import annotations

import numpy as np

from gearlab.api import MM, Fault, GearlabInputError, healthy_section, hookimpl, parameters, region, setting

# Default band: the upper flank, inside the active profile of both thesis pairs (contact
# starts at 0.34 d_h on the luo2019 pinion, 0.28 d_h on meng2020) and up to the tip.
BAND = (0.4, 1.0)


def thinnest_thickness(pair, band_start: float, band_end: float) -> float:
    """Smallest healthy tooth thickness 2 h_x of the pinion over the band (m)."""
    section = healthy_section(pair.pinion, pair.face_width)
    x0, x1 = band_start * section.tooth_height, band_end * section.tooth_height
    # the band ends too, in case no section node falls inside a narrow band
    h = np.concatenate([section.h[region(section, x0, x1)], np.interp([x0, x1], section.x, section.h)])
    return float(2 * h.min())


class Wear(Fault):
    name = "wear"
    doc = "Uniform wear of depth `depth` on the loaded flank over a band of the tooth height (fractions from the root)."
    params = parameters(
        depth=setting(float, 0.0, low=0.0, high=0.05, **MM, doc="wear depth, normal to the loaded flank"),
        band_start=setting(
            float, BAND[0], low=0.0, high=1.0, doc="start of the worn band, fraction of the tooth height from the root"
        ),
        band_end=setting(
            float, BAND[1], low=0.0, high=1.0, doc="end of the worn band, fraction of the tooth height from the root"
        ),
    )

    def check(self, params, pair, where):
        start, end = params["band_start"], params["band_end"]
        if start >= end:
            raise GearlabInputError(f"{where}: band_start = {start:g} must lie below band_end = {end:g}")
        # The static bound on `depth` cannot know the tooth: refuse wear through it here.
        thinnest = thinnest_thickness(pair, start, end)
        if params["depth"] >= thinnest:
            raise GearlabInputError(
                f"{where}: wear depth {params['depth'] * 1e3:g} mm eats the tooth: it is only "
                f"{thinnest * 1e3:.4g} mm thick at its thinnest in the band {start:g}..{end:g} of its height"
            )

    def apply(self, section, params, pair):
        depth = params["depth"]
        if depth <= 0:
            return section  # exactly the section it was given
        height = section.tooth_height
        on = region(section, params["band_start"] * height, params["band_end"] * height)
        h = section.h.copy()
        h[on] = np.maximum(h[on] - depth / 2, 0.0)  # one flank loses delta: half thickness delta/2
        # A and I scaled by the ratio of half thicknesses (A ~ h, I ~ h^3 for the strip), so that
        # wear also composes with a fault applied before it on the same tooth.
        ratio = np.divide(h, section.h, out=np.zeros_like(h), where=section.h > 0)
        return section.replace(h=h, A=section.A * ratio, I=section.I * ratio**3)

    def rfa(self, params, pair):
        """Relative fault area, eq. 2.113, in the transverse (profile) plane of the tooth.

        Eq. 2.113 takes the plane in which a fault acts. Wear covers its band across the
        whole face width, so in the face plane its share would be the band's share
        whatever the depth: every step of the ladder would read the same. In the profile
        plane the worn strip is delta (x1 - x0) of the tooth's area int 2 h_x dx, which grows
        with depth as a crack's share of the girth plane does. Since nothing varies across
        the face, this is also the share of the tooth's volume worn away.
        """
        healthy = healthy_section(pair.pinion, pair.face_width)
        worn = self.apply(healthy, params, pair)
        removed = np.trapezoid(healthy.A - worn.A, healthy.x)
        return float(np.clip(removed / np.trapezoid(healthy.A, healthy.x), 0.0, 1.0))

    def ladder_endpoints(self, pair):
        # 20 steps of growing depth on the default band, from none to the worst wear that
        # leaves the thinnest point of the band half its thickness.
        band = {"band_start": BAND[0], "band_end": BAND[1]}
        worst = 0.5 * thinnest_thickness(pair, *BAND)
        return {"depth": 0.0, **band}, {"depth": worst, **band}


@hookimpl
def gearlab_faults():
    return [Wear()]
