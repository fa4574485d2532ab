"""Geometry of a described spur stage (ISO 21771) and the checks a gear engineer makes first.

For a stage of module m, pressure angle α, tooth counts z1, z2 and profile shifts x1, x2:

    d = m z,  d_b = d cos α,  d_a = d + 2 m (h_a* + x) (or as given),  d_f = d - 2 m (h_f* - x)
    inv α_w = inv α + 2 tan α (x1 + x2) / (z1 + z2),   a_w = m (z1 + z2) cos α / (2 cos α_w)
    ε_α = (√(r_a1² - r_b1²) + √(r_a2² - r_b2²) - a_w sin α_w) / (π m cos α)

Checks, each a one-line error naming the key:

h_a*, h_f* and d_a are each gear's where given, else the stage's.

* centre distance: a given centre distance must equal a_w (the tooth counts, module and
  shifts fix it); the message says which tooth sum or shift sum would fit;
* undercut: x ≥ (5/6) h_a* - z sin²α / 2 (the practical limit of DIN 3960 / Niemann: slight
  undercut below the active flank is accepted, z ≥ 14 at 20 deg and x = 0; the interference check
  then asks that the mate's tip meets the involute). The textbook's limit of no undercut at all,
  x ≥ h_a* - z sin²α / 2, would refuse pinions that run well; the error names both;
* interference: the mating tip must meet each flank on its involute, above the form circle
  where the generating rack's straight flank ends (roll length L_F = r sin α - m (h_FfP* - x) / sin α,
  h_FfP* = h_f* - ρ_fP* (1 - sin α));
* tip clearance: a_w - r_a of one gear - r_f of the other ≥ 0 (a shifted pair's tips may reach
  the mating root: the message names the tip diameter or addendum that would clear it);
* contact ratio ε_α ≥ 1; pointed teeth (tip thickness s_a ≤ 0); a bore that cuts the root circle;
* face width: b ≤ 3 d1 (the pinion's reference diameter); a spur pinion's ψ_d = b / d1 is rarely over 1.5 (Niemann),
  as a wider face bends and twists under load; a face 25.4 x too wide, inches typed for millimetres, lies far over.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import GearlabInputError
from ..physics.geometry import inverse_involute, involute

# Slack on the practical undercut limit: at 20 deg and x = 0 it admits z = 14 (x_min' = 0.015).
_UNDERCUT_SLACK = 0.02
# A described centre distance agrees with a_w within this share of the module (or 10 µm).
_CENTRE_TOLERANCE = 0.02
# The widest face a stage may have, as a multiple of its pinion's reference diameter (module doc).
_FACE_PER_PINION_DIAMETER = 3.0


@dataclass(frozen=True)
class StageGeometry:
    """Diameters (m), operating pressure angle (rad), centre distances (m), contact ratio of a stage."""

    d: tuple[float, float]
    d_b: tuple[float, float]
    d_a: tuple[float, float]
    d_f: tuple[float, float]
    alpha_w: float
    a: float  # reference centre distance m (z1 + z2) / 2
    a_w: float  # operating centre distance
    contact_ratio: float
    tip_thickness: tuple[float, float]  # s_a
    roll_start: tuple[float, float]  # roll length from T_i on the line of action where contact starts
    roll_form: tuple[float, float]  # roll length of the form circle (end of the generated involute)

    def describe(self) -> dict:
        return {
            "d_mm": [v * 1e3 for v in self.d],
            "d_b_mm": [v * 1e3 for v in self.d_b],
            "d_a_mm": [v * 1e3 for v in self.d_a],
            "d_f_mm": [v * 1e3 for v in self.d_f],
            "alpha_w_deg": math.degrees(self.alpha_w),
            "a_mm": self.a * 1e3,
            "a_w_mm": self.a_w * 1e3,
            "contact_ratio": self.contact_ratio,
        }


def gear_addendum(stage, gear) -> float:
    """h_a* of *gear*: its own, else the stage's."""
    return stage.addendum if gear.addendum is None else gear.addendum


def gear_dedendum(stage, gear) -> float:
    """h_f* of *gear*: its own, else the stage's."""
    return stage.dedendum if gear.dedendum is None else gear.dedendum


def rack_addendum(stage, gear) -> float:
    """h_a of the rack that cut *gear* (its tooth below the reference line: h_f* - c*): the stage's
    h_a*, or the gear's own dedendum less the stage's clearance."""
    return stage.addendum if gear.dedendum is None else gear.dedendum - (stage.dedendum - stage.addendum)


def gear_tip(stage, gear) -> float:
    """d_a of *gear*: as given, else d + 2 m (h_a* + x)."""
    if gear.tip_diameter is not None:
        return gear.tip_diameter
    return stage.module * gear.z + 2 * stage.module * (gear_addendum(stage, gear) + gear.x)


def stage_geometry(stage) -> StageGeometry:
    m, alpha = stage.module, stage.pressure_angle
    gears = (stage.pinion, stage.wheel)
    z1, z2 = stage.pinion.z, stage.wheel.z
    x_sum = stage.pinion.x + stage.wheel.x
    alpha_w = inverse_involute(involute(alpha) + 2.0 * math.tan(alpha) * x_sum / (z1 + z2))
    a = 0.5 * m * (z1 + z2)
    a_w = a * math.cos(alpha) / math.cos(alpha_w)
    d = tuple(m * g.z for g in gears)
    d_b = tuple(v * math.cos(alpha) for v in d)
    d_a = tuple(gear_tip(stage, g) for g in gears)
    d_f = tuple(v - 2 * m * (gear_dedendum(stage, g) - g.x) for v, g in zip(d, gears))
    tip_roll = tuple(math.sqrt(max(0.0, (ra / 2) ** 2 - (rb / 2) ** 2)) for ra, rb in zip(d_a, d_b))
    line = a_w * math.sin(alpha_w)  # T1 T2, the line of action between the base-circle tangents
    epsilon = (tip_roll[0] + tip_roll[1] - line) / (math.pi * m * math.cos(alpha))
    roll_start = (line - tip_roll[1], line - tip_roll[0])
    rho = stage.tool_tip_radius * (1 - math.sin(alpha))  # h_FfP* = h_f* - ρ_fP* (1 - sin α)
    roll_form = tuple(
        v / 2 * math.sin(alpha) - m * (gear_dedendum(stage, g) - rho - g.x) / math.sin(alpha) for v, g in zip(d, gears)
    )
    s_a = []
    for va, vb, g in zip(d_a, d_b, gears):
        alpha_a = math.acos(min(1.0, vb / va))
        s_a.append(va * (math.pi / (2 * g.z) + 2 * g.x * math.tan(alpha) / g.z + involute(alpha) - involute(alpha_a)))
    return StageGeometry(d, d_b, d_a, d_f, alpha_w, a, a_w, epsilon, tuple(s_a), roll_start, roll_form)


def _mm(v: float, digits: int = 4) -> str:
    return f"{v * 1e3:.{digits}g} mm"


def check_geometry(box) -> None:
    """Raise on the first stage whose geometry cannot mesh (see the module doc)."""
    for stage in box.stages:
        check_stage(stage)


def check_stage(stage) -> StageGeometry:
    g = stage_geometry(stage)
    m, alpha = stage.module, stage.pressure_angle
    z1, z2 = stage.pinion.z, stage.wheel.z
    gears = (("pinion", stage.pinion), ("wheel", stage.wheel))
    x_sum = stage.pinion.x + stage.wheel.x
    for _, gear in gears:
        if gear.face_width > _FACE_PER_PINION_DIAMETER * g.d[0]:
            where = stage.where if gear.face_width == stage.face_width else gear.where
            raise GearlabInputError(
                f"{where} key 'face_width': {_mm(gear.face_width)} is {gear.face_width / g.d[0]:.3g} x the pinion's "
                f"reference diameter d1 = {_mm(g.d[0])} (z1 = {z1}, m = {_mm(m)}); expected at most "
                f"{_FACE_PER_PINION_DIAMETER:g} d1 = {_mm(_FACE_PER_PINION_DIAMETER * g.d[0])}, a spur pinion's face "
                f"rarely over 1.5 d1 (inches for millimetres? '{gear.face_width / 0.0254:.4g} mm')"
            )
    # Undercut, before the checks that an undercut tooth would fail in a less telling way.
    for _, gear in gears:
        h_rack = rack_addendum(stage, gear)
        x_min = 5.0 / 6.0 * h_rack - gear.z * math.sin(alpha) ** 2 / 2
        if gear.x < x_min - _UNDERCUT_SLACK:
            raise GearlabInputError(
                f"{gear.where} key 'z': {gear.z} teeth at x = {gear.x:g} are undercut into the active flank (α = "
                f"{math.degrees(alpha):g} deg, h_a* = {h_rack:g}; the practical limit x ≥ 5/6 h_a* - z sin²α/2 of "
                "DIN 3960 / Niemann, which accepts a slight undercut below the flank the mate's tip reaches; no "
                f"undercut at all: x ≥ h_a* - z sin²α/2 = {x_min + h_rack / 6:.3f}); "
                f"expected a profile shift 'x' ≥ {x_min:.3f}, more teeth, or a larger "
                "'pressure_angle' or shorter 'addendum' of the stage"
                + ("" if gear.dedendum is None else f" (or a smaller 'dedendum' of this gear: {gear.dedendum:g})")
            )
    if stage.centre_distance is not None:
        tolerance = max(_CENTRE_TOLERANCE * m, 1e-5)
        given = stage.centre_distance
        if abs(given - g.a_w) > tolerance:
            teeth = 2 * given / m
            fit = f"z1 + z2 = {teeth:.4g} at this module" + (
                "" if abs(teeth - round(teeth)) > 0.01 else f" ({round(teeth)} teeth)"
            )
            if abs(teeth - (z1 + z2)) <= 0.01:  # the teeth's zero-shift distance: the shifts' working one meant?
                fit = f"centre_distance = '{_mm(g.a_w, 5)}', the working centre distance of these shifts"
            cos_w = g.a * math.cos(alpha) / given
            shift = ""
            if 0 < cos_w < 1:
                x_fit = (involute(math.acos(cos_w)) - involute(alpha)) * (z1 + z2) / (2 * math.tan(alpha))
                if -1.5 < x_fit < 2.5:
                    shift = f", or a profile shift sum x1 + x2 = {x_fit:.3f}"
            raise GearlabInputError(
                f"{stage.where} key 'centre_distance': {_mm(given, 5)} contradicts z1 = {z1}, z2 = {z2}, m = {_mm(m)}, "
                f"x1 + x2 = {x_sum:g}, which mesh at a_w = {_mm(g.a_w, 5)}; expected {fit}{shift}"
            )
    for (_, gear), d_a, d_b, d_f in zip(gears, g.d_a, g.d_b, g.d_f):
        if d_a <= max(d_b, d_f):  # only a given tip diameter can be this small
            raise GearlabInputError(
                f"{gear.where} key 'tip_diameter': {_mm(d_a)} lies inside the "
                f"{'base' if d_b >= d_f else 'root'} circle ({_mm(max(d_b, d_f))}); expected a tip above both "
                f"(d_b = {_mm(d_b)}, d_f = {_mm(d_f)})"
            )
    for (_, gear), s_a in zip(gears, g.tip_thickness):
        if s_a <= 0:
            key = "tip_diameter" if gear.tip_diameter is not None else "addendum" if gear.addendum is not None else "x"
            raise GearlabInputError(
                f"{gear.where} key '{key}': the teeth are pointed (tip thickness {_mm(s_a)} at x = {gear.x:g}); "
                "expected a smaller profile shift or addendum" + (" or tip diameter" if key == "tip_diameter" else "")
            )
    for (_, gear), d_f in zip(gears, g.d_f):
        if gear.bore >= d_f:
            raise GearlabInputError(
                f"{gear.where} key 'bore': {_mm(gear.bore)} reaches the root circle d_f = {_mm(d_f)}; "
                "expected a bore smaller than the root diameter"
            )
    # Tip clearance: a shifted pair's tips may reach the mating root (ISO 21771's tip shortening).
    for (role, _), (other, mate), d_f, d_a in zip(gears, reversed(gears), g.d_f, reversed(g.d_a)):
        clearance = g.a_w - d_a / 2 - d_f / 2
        if clearance < -1e-12 * g.a_w:
            fit = 2 * g.a_w - d_f
            key = "tip_diameter" if mate.tip_diameter is not None else "addendum"
            h_fit = (fit - m * mate.z) / (2 * m) - mate.x
            raise GearlabInputError(
                f"{mate.where} key '{key}': the {other}'s tip (d_a = {_mm(d_a)}) reaches the {role}'s root circle "
                f"(d_f = {_mm(d_f)}; tip clearance {_mm(clearance)} at a_w = {_mm(g.a_w)}); expected a shortened tip: "
                f"the {other}'s 'tip_diameter' ≤ {math.floor(fit * 1e7) / 1e4:.4f} mm or 'addendum' ≤ "
                f"{math.floor(h_fit * 1e4) / 1e4:.4f}, or smaller shifts"
            )
    # Interference: the mating tip must meet each flank on its involute (above the form circle).
    for (role, gear), (other, mate), start, form in zip(gears, reversed(gears), g.roll_start, g.roll_form):
        limit = max(form, 0.0)
        if start < limit:
            where = "below its base circle" if start < 0 else "below the end of its involute (in the fillet)"
            raise GearlabInputError(
                f"{gear.where} key 'z': the {other}'s tip meets the {role} {where} (interference: contact starts "
                f"{_mm(start)} from T on the line of action, the involute at {_mm(limit)}); expected more {role} "
                f"teeth, a shorter 'addendum' (h_a* = {gear_addendum(stage, mate):g}) of the stage or the {other} (or "
                f"the {other}'s 'tip_diameter'), a larger 'pressure_angle' (α = {math.degrees(alpha):g} deg) of the "
                f"stage, or a positive profile shift 'x' of the {role}"
            )
    if g.contact_ratio < 1.0:
        # a gear whose own tip_diameter or addendum shortened its tip below the stage's: that key; else the stage
        short = [
            (gear, "tip_diameter" if gear.tip_diameter is not None else "addendum")
            for (_, gear), d_a in zip(gears, g.d_a)
            if d_a < m * gear.z + 2 * m * (stage.addendum + gear.x) - 1e-12
        ]
        where = f"{short[0][0].where} key '{short[0][1]}'" if short else stage.where
        raise GearlabInputError(
            f"{where}: contact ratio ε_α = {g.contact_ratio:.3f} below 1 (z1 = {z1}, z2 = {z2}, "
            f"α_w = {math.degrees(g.alpha_w):.3g} deg): the next tooth pair would engage only after the last "
            "lost contact; expected ε_α ≥ 1 (more teeth, a larger 'addendum' or 'tip_diameter', or a smaller "
            "'pressure_angle')"
        )
    return g
