"""speed_fluctuation: a shaft-synchronous fluctuation of the input speed.

Physical mismatch. The thesis fixes the input speed exactly (2.3: "the shaft speed and
motor torque are fixed"). A real drive's speed ripples: a motor's torque pulsation against
the drive-train inertia, coupling misalignment (twice per revolution), a cardan joint. The
ripple moves the mesh stiffness in time (frequency modulation of every mesh harmonic:
sidebands at multiples of q shaft orders) and accelerates every rotating inertia.

Realisation. The input shaft follows

    omega(t) = Omega (1 + eps sin(q Omega t + phi)),  Omega = 2 pi f,
    theta(t) = Omega t + (eps / q) (cos phi - cos(q Omega t + phi)),
    alpha(t) = eps q Omega^2 cos(q Omega t + phi).

With whole orders q the shaft still turns exactly once per 1/f, so the response stays
periodic in one revolution. The TVMS is read at theta(t) (decision 19: at the input
shaft's angle), the tacho reports theta(t), and, since all rotations are measured relative
to the rigid-body rotation of the input shaft, each rotating DOF feels the inertial torque
-I_i r_i alpha(t) with r_i = 1 on the input side and Z1/Z2 on the output side. The
revolution is then resampled at the true angle (order tracking).

Symmetry. The fluctuation is locked to the shaft angle but not to the tooth pitch: a fault
on tooth n meets the mesh at another speed than on tooth 1, so it breaks the tooth-shift
symmetry.

Bounds. eps from 0 (no fluctuation) to 0.1 (10 % peak speed ripple, a badly tuned drive);
order q = 1..32 (once-per-revolution unbalance/run-out to motor slot and pole harmonics);
phase 0..360 deg. Default 1 % at once per revolution.
"""

import math

import numpy as np

from gearlab.api import DEG, Effect, hookimpl, parameters, setting, setting_of

# Phases tried with a ripple's order read off the target: the sidebands' phases are in the
# record's tacho frame, turned by an offset a guess cannot know (the diagnosis fits it per set).
GUESS_PHASES = tuple(k * math.pi / 2 for k in range(4))
GUESS_AMPLITUDES = (0.003, 0.01, 0.03)  # a speed ripple's eps, a decade around the default


def sideband_ripple(target_X, highest: int) -> tuple[int, float] | None:
    """The order q (1..highest) of a ripple that modulates the mesh, read off the target's
    synchronous average, and its modulation index m: a ripple at q shaft orders puts sidebands at
    L +- q around every mesh harmonic L (a healthy gear has none). The mesh harmonics are the
    strong lines (1e3 above the median order) spaced by the most common gap between them (Z1);
    q is the offset up to half that spacing with the most sideband power (q and m Z1 +- q put
    sidebands on the same lines: the smallest stands for them all); m = sqrt(2 R),
    R the median over harmonics of the sideband pair's power against its line (an AM index:
    the load ripple's own amplitude). None when no mesh family is seen."""
    X = np.asarray(target_X, dtype=float)
    power = np.abs(np.fft.rfft(X.mean(axis=0)) / X.shape[1]) ** 2
    held = np.nonzero(power > 1e-12 * power.max())[0]
    if held.size < 2:
        return None
    power = power[: int(held.max()) + 1]  # a record's passband: above it, rounding
    floor = float(np.median(power[1:]))
    strong = sorted(int(k) for k in np.argsort(-power[1:])[:12] + 1 if power[k] > 1e3 * floor and k > highest)
    if len(strong) < 2:
        return None
    spacing = int(np.bincount(np.diff(strong)).argmax())
    lines = {k for k in strong if k % spacing == 0}
    top = power.size - 1
    best, best_q = 0.0, None
    # Orders q and m Z1 +- q put sidebands on the same lines: the smallest stands for them all.
    for q in range(1, min(highest, spacing // 2) + 1):
        side = sum(power[s] for k in lines for s in (k - q, k + q) if 0 < s <= top and s not in lines)
        if side > best:
            best, best_q = side, q
    if best_q is None:
        return None
    ratios = [
        (power[k - best_q] + power[k + best_q]) / power[k]
        for k in lines
        if k + best_q <= top and k - best_q not in lines and k + best_q not in lines
    ]
    return best_q, float(np.sqrt(2.0 * np.median(ratios))) if ratios else 0.0


class ShaftRipple(Effect):
    """A ripple eps sin(q Omega t + phi) at whole orders q of the input shaft (this module's speed
    ripple, load_fluctuation's load ripple): locked to the shaft angle, not to the tooth pitch."""

    breaks_symmetry = True
    # The record sees the phase only up to turns by whole tooth pitches: phi and phi + 2 pi q j / Z1
    # differ by a few percent of the revolution once the tacho offset is fitted (gearlab.gap.identify.alias_refit).
    pitch_aliases = ("phase", "order")

    @staticmethod
    def ripple_params(what: str, default: float, high: float, orders: int) -> type:
        """The settings dataclass of eps (relative peak of *what*, *default*, 0 .. *high*), q (1 ..
        *orders*) and phi."""
        return parameters(
            amplitude=setting(float, default, low=0.0, high=high, doc=f"relative peak {what} fluctuation eps"),
            order=setting(int, 1, low=1, high=orders, doc="fluctuation frequency in input-shaft orders q"),
            phase=setting(float, 0.0, low=0.0, high=2 * math.pi, **DEG, doc="phase phi at the first tacho zero"),
        )

    def apply_excitation(self, exc, params):
        eps, q, phi = params["amplitude"], params["order"], params["phase"]
        return exc if eps == 0.0 else self.rippled(exc, eps, q, phi)

    def rippled(self, exc, eps: float, q: int, phi: float):
        """*exc* with the ripple of relative amplitude eps > 0, order q and phase phi."""
        raise NotImplementedError


class SpeedFluctuation(ShaftRipple):
    name = "speed_fluctuation"
    doc = "input speed ripple eps at whole shaft order q: moved TVMS, tacho and inertial torques"
    params = ShaftRipple.ripple_params("speed", 0.01, 0.1, 32)

    def rippled(self, exc, eps, q, phi):
        omega = 2 * math.pi * exc.speed_hz
        wt = q * omega * exc.t + phi
        angle = exc.angle + eps / q * (math.cos(phi) - np.cos(wt))
        alpha = eps * q * omega**2 * np.cos(wt)
        return exc.with_angle(angle).add_force(lambda e: (-(e.M @ e.rigid_rotation()), alpha))

    def guesses(self, target_X, speed_hz):
        """The ripple's order from the mesh sidebands (:func:`sideband_ripple`), at GUESS_AMPLITUDES
        and two of GUESS_PHASES: order tracking takes the angle modulation out of the record, so
        the sidebands left (inertial torques, the dynamics) do not give eps simply."""
        found = sideband_ripple(target_X, int(setting_of(self.params, "order").high))
        if found is None:
            return []
        return [
            {"order": found[0], "amplitude": eps, "phase": phase}
            for eps in GUESS_AMPLITUDES
            for phase in GUESS_PHASES[::2]
        ]


@hookimpl
def gearlab_effects():
    return [SpeedFluctuation()]
