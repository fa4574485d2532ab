"""The order table of a gearbox: what a vibration spectrum should hold, in input-shaft orders.

An order is one cycle per input-shaft revolution. For a series train with stage k's pinion
(z_k,1 teeth) on shaft k and its wheel (z_k,2) on shaft k + 1:

    shaft orders      o_1 = 1,  o_{k+1} = o_k z_k,1 / z_k,2          (exact fractions)
    mesh orders       M_k = o_k z_k,1 = o_{k+1} z_k,2
    sidebands         h M_k ± j o_k  and  h M_k ± j o_{k+1}           (modulation by either shaft)
    hunting tooth     a tooth pair meets again after z_k,2 / g pinion turns, g = gcd(z_k,1, z_k,2)
                      (the assembly phase factor); in input turns (z_k,2 / g) / o_k
    train period      all shafts back at their start angles together after Q input turns,
                      Q = lcm of the denominators of the o_k

Fractions keep the orders exact, so that a record's lines can be tested against them as
closely as its resolution allows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction


@dataclass(frozen=True)
class StageOrders:
    index: int  # 1-based
    pinion_teeth: int
    wheel_teeth: int
    pinion_shaft: str
    wheel_shaft: str
    mesh: Fraction  # M_k, input orders
    pinion_shaft_order: Fraction
    wheel_shaft_order: Fraction
    assembly_phase: int  # g = gcd(z1, z2)
    hunting_input_turns: Fraction  # input revolutions between meetings of the same tooth pair

    def sidebands(self, harmonics: int = 3, count: int = 3) -> list[tuple[str, float]]:
        """(label, order) of h M_k ± j o for both shafts of the stage (h = 1 … harmonics, j = 1 … count)."""
        out = []
        for h in range(1, harmonics + 1):
            for shaft, o in ((self.pinion_shaft, self.pinion_shaft_order), (self.wheel_shaft, self.wheel_shaft_order)):
                for j in range(1, count + 1):
                    for sign in (-1, 1):
                        value = h * self.mesh + sign * j * o
                        if value > 0:
                            mesh = f"{h if h > 1 else ''}M{self.index}"
                            label = f"{mesh} {'+' if sign > 0 else '-'} {j if j > 1 else ''}{shaft}"
                            out.append((label, float(value)))
        return out


@dataclass(frozen=True)
class OrderTable:
    shafts: tuple[str, ...]
    shaft_orders: tuple[Fraction, ...]
    stages: tuple[StageOrders, ...]
    train_period: int  # input revolutions after which every shaft is back at its start angle

    def lines(self, harmonics: int = 3, sidebands: int = 3, shaft_harmonics: int = 3) -> list[tuple[str, float]]:
        """Every (label, order) the description explains: shaft harmonics, mesh harmonics, sidebands."""
        out = []
        for name, o in zip(self.shafts, self.shaft_orders):
            out += [(f"{h if h > 1 else ''}{name}", float(h * o)) for h in range(1, shaft_harmonics + 1)]
        for s in self.stages:
            out += [(f"{h if h > 1 else ''}M{s.index}", float(h * s.mesh)) for h in range(1, harmonics + 1)]
            out += s.sidebands(harmonics, sidebands)
        return out

    def describe(self, speed_hz: float | None = None) -> dict:
        def hz(o):
            return None if speed_hz is None else float(o) * speed_hz

        return {
            "shafts": [
                {"name": n, "order": float(o), "fraction": str(o), "hz": hz(o)}
                for n, o in zip(self.shafts, self.shaft_orders)
            ],
            "stages": [
                {
                    "stage": s.index,
                    "z1": s.pinion_teeth,
                    "z2": s.wheel_teeth,
                    "mesh_order": float(s.mesh),
                    "mesh_fraction": str(s.mesh),
                    "mesh_hz": hz(s.mesh),
                    "assembly_phase_factor": s.assembly_phase,
                    "hunting_tooth_input_revolutions": float(s.hunting_input_turns),
                    "hunting_tooth_hz": None if speed_hz is None else speed_hz / float(s.hunting_input_turns),
                }
                for s in self.stages
            ],
            "train_period_input_revolutions": self.train_period,
        }


def order_table(box) -> OrderTable:
    """The order table of the description *box* (gearlab.gearbox.description.Gearbox)."""
    orders = [Fraction(1)]
    stages = []
    for k, stage in enumerate(box.stages):
        z1, z2 = stage.pinion.z, stage.wheel.z
        o = orders[-1]
        g = math.gcd(z1, z2)
        stages.append(
            StageOrders(
                index=stage.index,
                pinion_teeth=z1,
                wheel_teeth=z2,
                pinion_shaft=box.shafts[k],
                wheel_shaft=box.shafts[k + 1],
                mesh=o * z1,
                pinion_shaft_order=o,
                wheel_shaft_order=o * Fraction(z1, z2),
                assembly_phase=g,
                hunting_input_turns=Fraction(z2 // g) / o,
            )
        )
        orders.append(o * Fraction(z1, z2))
    period = math.lcm(*(o.denominator for o in orders))
    return OrderTable(tuple(box.shafts), tuple(orders), tuple(stages), period)


@dataclass(frozen=True)
class TachoShaft:
    """The shaft a tacho reads, turning a/b times per input turn: the tacho's angle / (a/b) is the
    input's, a continuous phase, b/a input turns a tacho turn whether whole or not."""

    name: str
    a: int = 1
    b: int = 1

    @classmethod
    def of(cls, box, name: str, where: str) -> TachoShaft:
        """Shaft *name* of the description *box*; a one-line error naming *where* and the shafts known."""
        turns = order_table(box).shaft_orders[box.shaft_index(name, where)]
        return cls(name, turns.numerator, turns.denominator)

    @property
    def turns(self) -> Fraction:
        return Fraction(self.a, self.b)

    def marks(self, pulses_per_rev: int = 1) -> int:
        """M: a record's input angle at its first tacho mark is known to 1/M of a turn. With N marks per
        turn, the j-th mark finds the input j b / (a N) turns on: M = N a / gcd(b, N). N on the input;
        1 for one mark of a shaft turning once in b whole input turns; 16 for a 16/49 stage's output
        (49/16 input turns a mark); a shaft angle reads as N = 1."""
        return pulses_per_rev * self.a // math.gcd(self.b, pulses_per_rev)


def settle_turns(box) -> int:
    """The input turns of the description *box*'s slowest shaft's turn (1 without one), the level a record's
    start-up is judged over (signals.steady_start_stats): judged turn by turn, a steady 37/89 box's level, its
    output shaft's 2.4 turns modulating the mesh, swung out of the 5 % band, and every take of a user's 37/89 and
    29/101 + 33/107 boxes read with a tacho 'never settles' in a gap or detection run."""
    return 1 if box is None else math.ceil(1 / min(order_table(box).shaft_orders))
