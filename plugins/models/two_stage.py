"""The two-stage model of the PHM 2009 spur rig: the 10-DOF model (thesis 2.3) with a second mesh.

Stage 1 is the thesis's pair (input pinion 32T -> idler gear 96T); the idler shaft carries a
48T pinion that drives the 80T output gear (stage 2), whose shaft drives the load through a
coupling. The DOFs, eq. 2.96 extended by the output block (x3, y3, theta31):

    x1, y1, theta11 (motor), theta12 (input pinion), x2, y2, theta21 (idler: 96T gear and 48T
    pinion, one rigid block), x3, y3, theta31 (output gear), theta22 (load), xf, yf (casing).

theta22 keeps its thesis meaning, the load, so the effects that act on the drive (drive_inertias,
load_fluctuation) act on this model unchanged. All three shafts sit in bearings on the casing
(k_b, c_b, eq. 2.100), the casing on its mounting (k_xf, k_yf); the sensor is on the casing.

Stage 1's line of action is eq. 2.104's. Stage 2 (the layout is a reverted train, presets.py):
its centre line points back from the idler to the output, and its driver turns the other way,
so its line of action is stage 1's rotated by 180 deg and mirrored about the centre line,

    delta_2 = (x2 - x3) sin a0 - (y2 - y3) cos a0 + R_b3 theta21 - R_b4 theta31,

each rotation measured positive in its own gear's direction of turning (as in eq. 2.104). Its
stiffness k_2(t) is the potential-energy TVMS of the 48/80 pair at the idler's angle (1/3 of the
input's), so the 16x input-order mesh is physics. The assembly is a rank-two update of the
constant matrices; gearlab.dynamics.newmark integrates it exactly (Woodbury, one 2 x 2 system
per step).

A two-stage gearbox description (gearlab.gearbox.simulation) runs on this model with its own two
pairs (StagePair.next_stage) and the same layout: stage 2's centre line anti-parallel to stage 1's.

Symmetry: the stage-2 mesh repeats every 2 pinion pitches (16 per input turn), so the response
to a chip on tooth n is not tooth 1's shifted by (n - 1)/32 turn (breaks_symmetry).
"""

import math

import numpy as np

from gearlab.api import Assembly, DescribedPresets, DynamicModel, Mesh, add_spring, gear_pair, hookimpl

DOFS = ("x1", "y1", "theta11", "theta12", "x2", "y2", "theta21", "x3", "y3", "theta31", "theta22", "xf", "yf")

# The rig's lumped parameters live in its description, gearlab/gearbox/presets/phm09.toml (their
# sources: docs/real_data.md, "The rig simulator"); here the operating points of its datasets.
# Load: output torque, not published ("High"/"Low"); the diagnosis fits the level (load_level).
PHM09 = {"speeds_hz": (30.0, 40.0), "loads_nm": (20.0,)}


class TwoStage(DynamicModel):
    name = "two_stage"
    doc = (
        "two-stage spur gearbox (32/96 then 48/80 on a shared idler): the 10-DOF model with a second mesh "
        "and an output block; sensor on the casing; PHM 2009 rig"
    )
    dofs = DOFS
    input_dof = "theta11"
    load_dof = "theta22"
    stages = 2
    breaks_symmetry = True

    def param_names(self):
        return (
            "m1",
            "m2",
            "m3",
            "I12",
            "I21",
            "I31",
            "k_b",
            "c_b",
            "zeta",
            "I11",
            "I22",
            "k_c",
            "c_c",
            "mf",
            "k_xf",
            "k_yf",
            "c_xf",
            "c_yf",
        )

    def second_pair(self, pair):
        """The stage-2 pair of the preset whose stage 1 is *pair*: a description's carries it (next_stage)."""
        if getattr(pair, "next_stage", None) is not None:
            return pair.next_stage
        return gear_pair(next(p["pair2"] for p in self.presets.values() if p["pair"] == pair.name))

    def assemble(self, pair, values):
        return two_stage_assembly(pair, self.second_pair(pair), values)


def two_stage_assembly(pair, pair2, v) -> Assembly:
    """M, Kc, Cc (eq. 2.97, 2.100, 2.101 extended), stage 1's P (eq. 2.104) and stage 2's mesh."""
    idx = {d: i for i, d in enumerate(DOFS)}
    n = len(DOFS)
    M = np.diag(
        [
            v["m1"],
            v["m1"],
            v["I11"],
            v["I12"],
            v["m2"],
            v["m2"],
            v["I21"],
            v["m3"],
            v["m3"],
            v["I31"],
            v["I22"],
            v["mf"],
            v["mf"],
        ]
    )
    K, C = np.zeros((n, n)), np.zeros((n, n))

    def spring(a, b, k, c):
        add_spring(K, C, idx[a], None if b is None else idx[b], k, c)

    for block in ("1", "2", "3"):
        spring("x" + block, "xf", v["k_b"], v["c_b"])
        spring("y" + block, "yf", v["k_b"], v["c_b"])
    spring("xf", None, v["k_xf"], v["c_xf"])
    spring("yf", None, v["k_yf"], v["c_yf"])
    spring("theta11", "theta12", v["k_c"], v["c_c"])
    spring("theta31", "theta22", v["k_c"], v["c_c"])
    s1, c1 = math.sin(pair.pressure_angle), math.cos(pair.pressure_angle)
    P = np.zeros(n)
    for dof, value in (
        ("x1", s1),
        ("y1", c1),
        ("theta12", pair.pinion.R_b),
        ("x2", -s1),
        ("y2", -c1),
        ("theta21", -pair.gear.R_b),
    ):
        P[idx[dof]] = value  # eq. 2.104
    s2, c2 = math.sin(pair2.pressure_angle), math.cos(pair2.pressure_angle)
    P2 = np.zeros(n)
    for dof, value in (
        ("x2", s2),
        ("y2", -c2),
        ("theta21", pair2.pinion.R_b),
        ("x3", -s2),
        ("y3", c2),
        ("theta31", -pair2.gear.R_b),
    ):
        P2[idx[dof]] = value
    r1 = pair.pinion.R_b / pair.gear.R_b  # idler turns per input turn (1/3)
    r2 = r1 * pair2.pinion.R_b / pair2.gear.R_b  # output turns per input turn (1/5)
    return Assembly(
        DOFS,
        M,
        K,
        C,
        P,
        "theta11",
        "theta22",
        meshes=(Mesh(pair2, P2, r1, ("m2", "m3")),),
        rigid={"theta11": 1.0, "theta12": 1.0, "theta21": r1, "theta31": r2, "theta22": r2},
    )


TwoStage.presets = DescribedPresets(TwoStage(), {"phm09": PHM09})


@hookimpl
def gearlab_models():
    return [TwoStage()]
