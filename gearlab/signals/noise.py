"""Noise at a given SNR (thesis 4.1.1, eq. 4.1–4.5) and time-synchronous averaging (eq. 4.7).

Noise model. The thesis does not relate the parameters of each distribution to its RMS;
it draws *standard* noise and rescales it:

    SNR = (RMS_signal / RMS_noise)²                                          (4.1)
    SNR_dB = 10 log10(SNR)                                                   (4.2)
    RMS_noise,required = RMS_signal × 10^(−SNR_dB/20)                        (4.3)
    SF = RMS_noise,required / RMS_noise,default                              (4.4)
    x_{i,j} = s_{i,j} + SF · n_default                                       (4.5)

with RMS_noise,default the RMS of the drawn standard noise itself (not of its
distribution), so every noisy revolution s_{i,j} gets noise of exactly the required RMS.
The standard distributions (4.1.1): Gaussian with zero mean and unit variance, Laplace with
location 0 and scale 1, Student-t with ν = 2 degrees of freedom (infinite variance: the
per-revolution rescaling is what makes its level comparable; its impulses remain).
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np

from ..errors import GearlabInputError
from .checks import check_array, check_finite, check_real

NOISE_KINDS = ("gaussian", "laplace", "student_t")
# The SNRs a measurement noise may have: a dataset's noise and the sensor_noise effect alike
# (one declaration; the effect's docstring says why these)
SNR_DB_RANGE = (-20.0, 80.0)

_STANDARD_NOISE = {
    "gaussian": lambda rng, shape: rng.standard_normal(shape),
    "laplace": lambda rng, shape: rng.laplace(0.0, 1.0, shape),
    "student_t": lambda rng, shape: rng.standard_t(2.0, shape),
}


def _rms(x: np.ndarray) -> np.ndarray:
    """Root mean square along the last axis (time), one value per row: np.mean's sum and division (bit for
    bit) without its Python layer (twice a call of add_noise, 28,000 calls in a gap search's tests)."""
    return np.sqrt(np.add.reduce(x * x, axis=-1, keepdims=True) / x.shape[-1])


# Standard noise drawn before, by the state of the generator that drew it: (kind, shape, state) -> (noise,
# its rows' RMS, the generator's state after the draw). A gap search adds the source's sensor noise to
# every candidate's rows with the rows' own seeds ([seed, effect, row]): the same draws at every
# evaluation (21,210 draws, 9.7 s of CPU, in seven test files' gap fits and detections). Given again
# the same state a generator draws the same numbers: the kept ones are returned and the generator
# is left where the draw leaves it, so every later draw is as before. At most _DRAWN_BYTES, least
# recently used out first.
_DRAWN: OrderedDict = OrderedDict()
_DRAWN_BYTES = 1 << 26
_drawn_size = [0]  # the bytes of the noise kept


def _frozen(state):
    """A bit generator's state (nested dicts of ints, strings and arrays) as a dictionary key."""
    if isinstance(state, dict):
        return tuple((k, _frozen(v)) for k, v in sorted(state.items()))
    if isinstance(state, np.ndarray):
        return (state.dtype.str, state.shape, state.tobytes())
    return state


def _standard_noise(kind: str, rng: np.random.Generator, shape: tuple) -> tuple[np.ndarray, np.ndarray]:
    """(standard noise of *kind* and *shape* drawn by *rng*, its rows' RMS), kept by the generator's state."""
    bits = rng.bit_generator
    key = (kind, shape, _frozen(bits.state))
    kept = _DRAWN.get(key)
    if kept is not None:
        _DRAWN.move_to_end(key)
        bits.state = kept[2]
        return kept[0], kept[1]
    noise = _STANDARD_NOISE[kind](rng, shape)
    noise.flags.writeable = False
    rms = _rms(noise)
    _DRAWN[key] = (noise, rms, bits.state)
    _drawn_size[0] += noise.nbytes
    while _drawn_size[0] > _DRAWN_BYTES and len(_DRAWN) > 1:
        _drawn_size[0] -= _DRAWN.popitem(last=False)[1][0].nbytes
    return noise, rms


def add_noise(x: np.ndarray, snr_db: float, kind: str, rng: np.random.Generator) -> np.ndarray:
    """x + noise, each row (last axis = time/angle) at its own SNR_dB of *snr_db* (eq. 4.1–4.5).

    For every row s_{i,j}: draw standard noise of *kind* (one of NOISE_KINDS), scale it by
    SF = RMS_signal(row) × 10^(−SNR_dB/20) / RMS(drawn noise) and add it. The result is
    float64 and deterministic given the state of *rng*.
    """
    if kind not in NOISE_KINDS:
        raise GearlabInputError(f"unknown noise kind '{kind}'; known: {', '.join(NOISE_KINDS)}")
    if not isinstance(rng, np.random.Generator):
        raise GearlabInputError(
            f"rng must be a numpy.random.Generator (e.g. numpy.random.default_rng(seed)), got {type(rng).__name__}"
        )
    s = check_array(x, "signal", finite=False)
    rms_signal = _rms(s)
    if not np.isfinite(rms_signal).all():  # a NaN or inf in a row makes its RMS one: named here
        check_finite(s, "signal")
    snr_db = check_real(snr_db, "SNR (dB)")
    noise, rms_noise = _standard_noise(kind, rng, s.shape)
    rms_required = rms_signal * 10.0 ** (-snr_db / 20.0)  # eq. 4.3
    scale = rms_required / rms_noise  # eq. 4.4
    out = scale * noise  # eq. 4.5, x = s + SF n: the sum into the product's array (one record-sized array, not two)
    out += s
    return out


def tsa(revolutions: np.ndarray, axis: int = -2) -> np.ndarray:
    """Time-synchronous average y_i = Σ_j x_{n|i,j} / J over the J revolutions on *axis* (eq. 4.7).

    Revolutions must be aligned to the same shaft angle (they are, after
    :func:`resample_revolutions`): the shaft-synchronous response adds coherently while
    independent noise averages down, its RMS by √J. Float64 result.
    """
    r = check_array(revolutions, "revolutions", min_ndim=2)
    if not -r.ndim <= axis < r.ndim:
        raise GearlabInputError(f"revolution axis {axis} does not exist for an array of shape {r.shape}")
    return np.mean(r, axis=axis, dtype=np.float64)
