"""The multi-stage spur trains: the 10-DOF model (thesis 2.3) with a second mesh (two_stage, the PHM
2009 rig) or a second and a third (three_stage, a gearbox description's three-stage train).

The rig's stage 1 is the thesis's pair (input pinion 32T -> idler gear 96T); the idler shaft carries
a 48T pinion that drives the 80T output gear (stage 2), whose shaft drives the load through a
coupling. Each shaft carries one rigid block (its gears, shaft and bearings); the DOFs, eq. 2.96
extended shaft by shaft:

    x1, y1, theta11 (motor), theta12 (input pinion)           shaft 1, the input
    x2, y2, theta21 (stage 1's wheel, stage 2's pinion)       shaft 2 (the rig's idler)
    x4, y4, theta41 (stage 2's wheel, stage 3's pinion)       shaft 3 (three stages only)
    x3, y3, theta31 (the last stage's wheel)                  the output shaft
    theta22 (load), xf, yf (casing).

Blocks 1 and 2 are the thesis's, 3 the output block the two-stage model added, 4 the block a third
stage adds: the output block (channels output_x, output_y) and the load coupling theta31-theta22
are the same DOFs in both models, and two_stage is three_stage without block 4. theta22 keeps its
thesis meaning, the load, so the effects that act on the drive (drive_inertias, load_fluctuation)
act on these models unchanged. Every shaft sits in bearings on the casing (k_b, c_b, eq. 2.100),
the casing on its mounting (k_xf, k_yf); the sensor is on the casing.

Layout: a reverted train, zigzagged for three stages. Each stage's centre line points back,
anti-parallel to the one before, and each driver turns opposite to the one before, so stage 2's
line of action is stage 1's (eq. 2.104) rotated by 180 deg and mirrored about the centre line, and
stage 3's (anti-parallel to stage 2's) is stage 1's again. With the driving pinion's block d and
the driven wheel's w of stage k,

    delta_k = (x_d - x_w) sin a_k + s_k (y_d - y_w) cos a_k + R_b,d theta_d - R_b,w theta_w,

s_k = +1 for stages 1 and 3, -1 for stage 2 (for stage 1 this is eq. 2.104), each rotation measured
positive in its own gear's direction of turning. Stage k's stiffness k_k(t) is the potential-energy
TVMS of its pair at its pinion's angle (its shaft's turns per input turn, Mesh.ratio: 1/3 for the
rig's idler), so the rig's 16x input-order mesh is physics; its damping follows eq. 2.107 with the
masses of blocks d and w. The further meshes are a rank-(N - 1) update of the constant matrices;
gearlab.dynamics.newmark integrates them exactly (Woodbury, one N x N system per step).

At the static equilibrium each stage passes the torque on: f_k R_b,w(k) = f_(k+1) R_b,d(k+1), and
the last f_N R_b,w(N) = T_l (tests/test_two_stage.py, tests/test_three_stage.py).

A description (gearlab.gearbox.simulation) of two or three stages runs on these models with its
own pairs (stage 1's carries the next: StagePair.next_stage) and this layout; its blocks' masses
and inertias are its [[shafts]] values, else its gears as solid discs (gearbox.derive).

Symmetry: the rig's stage-2 mesh repeats every 2 pinion pitches (16 per input turn), so the
response to a chip on tooth n is not tooth 1's shifted by (n - 1)/32 turn (breaks_symmetry).
"""

import math

import numpy as np

from gearlab.api import Assembly, DescribedPresets, DynamicModel, GearlabInputError, Mesh, add_spring, hookimpl

# The block on each shaft, input first (x{b}, y{b}, theta{b}1, m{b}, I{b}1; block 1's rotation: theta12).
SHAFT_BLOCKS = {2: ("1", "2", "3"), 3: ("1", "2", "4", "3")}


def train_dofs(stages: int) -> tuple[str, ...]:
    """The DOFs of a train of *stages* stages (module doc), input first."""
    dofs = ["x1", "y1", "theta11", "theta12"]
    for b in SHAFT_BLOCKS[stages][1:]:
        dofs += [f"x{b}", f"y{b}", f"theta{b}1"]
    return (*dofs, "theta22", "xf", "yf")


DOFS = train_dofs(2)

# The rig's lumped parameters live in its description, gearlab/gearbox/presets/phm09.toml (their
# sources: docs/real_data.md, "The rig simulator"); here the operating points of its datasets.
# Load: output torque, not published ("High"/"Low"); the diagnosis fits the level (load_level).
PHM09 = {"speeds_hz": (30.0, 40.0), "loads_nm": (20.0,)}

_DRIVE = ("k_b", "c_b", "zeta", "I11", "I22", "k_c", "c_c", "mf", "k_xf", "k_yf", "c_xf", "c_yf")


class Train(DynamicModel):
    """A train of *stages* spur stages (module doc)."""

    input_dof = "theta11"
    load_dof = "theta22"
    breaks_symmetry = True

    def param_names(self):
        blocks = SHAFT_BLOCKS[self.stages]
        masses = tuple(f"m{b}" for b in blocks)
        return (*masses, *("I12" if b == "1" else f"I{b}1" for b in blocks), *_DRIVE)

    def pairs(self, pair) -> list:
        """Stage 1's *pair* and the pairs it carries (StagePair.next_stage), one per stage."""
        pairs = [pair]
        while len(pairs) < self.stages:
            after = getattr(pairs[-1], "next_stage", None)
            if after is None:
                raise GearlabInputError(
                    f"model '{self.name}': gear pair {pair.name!r} carries {len(pairs)} stage(s), the model meshes "
                    f"{self.stages}; give a gearbox description of {self.stages} stages"
                )
            pairs.append(after)
        return pairs

    def assemble(self, pair, values):
        return train_assembly(self.pairs(pair), values)


class TwoStage(Train):
    name = "two_stage"
    doc = (
        "two-stage spur gearbox (32/96 then 48/80 on a shared idler): the 10-DOF model with a second mesh "
        "and an output block; sensor on the casing; PHM 2009 rig"
    )
    dofs = DOFS
    stages = 2


class ThreeStage(Train):
    name = "three_stage"
    doc = (
        "three-stage spur gearbox: two_stage with a third mesh and a block on the second intermediate shaft "
        "(x4, y4, theta41); sensor on the casing; a gearbox description's three stages"
    )
    dofs = train_dofs(3)
    stages = 3


def _block_params(b: str) -> tuple[str, str, str]:
    """(rotation DOF, mass, inertia) of block *b*."""
    return ("theta12", "m1", "I12") if b == "1" else (f"theta{b}1", f"m{b}", f"I{b}1")


def train_assembly(pairs, v) -> Assembly:
    """M, Kc, Cc (eq. 2.97, 2.100, 2.101 extended), stage 1's P (eq. 2.104) and the further meshes."""
    blocks = SHAFT_BLOCKS[len(pairs)]
    dofs = train_dofs(len(pairs))
    idx = {d: i for i, d in enumerate(dofs)}
    n = len(dofs)
    inertia = {"theta11": "I11", "theta22": "I22", "xf": "mf", "yf": "mf"}
    for b in blocks:
        theta, mass, moment = _block_params(b)
        inertia.update({f"x{b}": mass, f"y{b}": mass, theta: moment})
    M = np.diag([v[inertia[d]] for d in dofs])
    K, C = np.zeros((n, n)), np.zeros((n, n))

    def spring(a, b, k, c):
        add_spring(K, C, idx[a], None if b is None else idx[b], k, c)

    for block in blocks:
        spring("x" + block, "xf", v["k_b"], v["c_b"])
        spring("y" + block, "yf", v["k_b"], v["c_b"])
    spring("xf", None, v["k_xf"], v["c_xf"])
    spring("yf", None, v["k_yf"], v["c_yf"])
    spring("theta11", "theta12", v["k_c"], v["c_c"])
    spring("theta31", "theta22", v["k_c"], v["c_c"])
    projections, meshes = [], []
    turns, rigid = 1.0, {"theta11": 1.0, "theta12": 1.0}
    for k, pair in enumerate(pairs, start=1):
        d, w = blocks[k - 1], blocks[k]  # the driving pinion's block and the driven wheel's
        (d_theta, d_mass, _), (w_theta, w_mass, _) = _block_params(d), _block_params(w)
        s, c = math.sin(pair.working_pressure_angle), math.cos(pair.working_pressure_angle)  # alpha_w: shifted gears
        cy = c if k % 2 else -c  # s_k of the module doc: stage 2's line of action mirrored
        P = np.zeros(n)
        for dof, value in (
            (f"x{d}", s),
            (f"y{d}", cy),
            (d_theta, pair.pinion.R_b),
            (f"x{w}", -s),
            (f"y{w}", -cy),
            (w_theta, -pair.gear.R_b),
        ):
            P[idx[dof]] = value  # eq. 2.104 for stage 1
        if k > 1:  # its pinion turns as its shaft: *turns* per input turn
            meshes.append(Mesh(pair, P, turns, (d_mass, w_mass)))
        projections.append(P)
        turns = turns * pair.pinion.R_b / pair.gear.R_b  # the driven shaft's turns per input turn (rig: 1/3, 1/5)
        rigid[w_theta] = turns
    rigid["theta22"] = turns
    return Assembly(dofs, M, K, C, projections[0], "theta11", "theta22", meshes=tuple(meshes), rigid=rigid)


TwoStage.presets = DescribedPresets(TwoStage(), {"phm09": PHM09})
# No built-in three-stage gearbox: three_stage runs a description's (`gearbox = "my.toml"`, --gearbox).
ThreeStage.presets = {}


@hookimpl
def gearlab_models():
    return [TwoStage(), ThreeStage()]
