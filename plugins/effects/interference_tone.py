"""interference_tone: a non-synchronous tone from a nearby machine (thesis chapter 4 introduction).

Physical mismatch. "Data captured on an industrial gearbox may be affected by ... vibrational
excitation from nearby machines": a motor, pump or fan on the same foundation adds a line at
its own running frequency, which is not a multiple of the gearbox's shaft speed. It is a
sinusoid of fixed amplitude in time,

    x(t) += sqrt(2) A_rms sin(2 pi f_i t),   A_rms = ratio x RMS of the domain's healthy signal,

with t the time of the record (t0 is random per record, so its phase differs from sample to
sample). In the order domain it is a line at the non-integer order f_i / f_shaft in every
revolution, and TSA over J revolutions attenuates it (it is not shaft-synchronous). Its
level is given relative to the healthy signal's RMS so the same parameters mean the same
thing on a pinion (~100 m/s^2) and a casing (~0.1 m/s^2) channel.

Bounds. Frequency from 1 Hz to 20 kHz (foundation-borne vibration of other machines and the
usable band of accelerometers); it must lie below the Nyquist frequency of the record
(4096 x shaft speed / 2). Level ratio 0 (no tone) to 10 (a neighbour far louder than the
gearbox). Defaults: 24.75 Hz, a 4-pole induction motor on 50 Hz mains at 1 % slip, and a
ratio of 0.5.
"""

from functools import lru_cache

import numpy as np

from gearlab.api import Effect, GearlabInputError, SignalContext, hookimpl, parameters, setting, setting_of

RATIO_LADDER = (0.5, 0.7, 1.4, 2.0)  # the guessed level's neighbours tried at the record's frequency
ZOOM = 201  # points of the zoomed record spectrum over two record bins around its peak


class InterferenceTone(Effect):
    name = "interference_tone"
    doc = "non-synchronous sinusoid from a nearby machine, level relative to the healthy signal RMS"
    params = parameters(
        frequency=setting(
            float, 24.75, low=1.0, high=2e4, unit="Hz", doc="frequency of the interfering machine's line"
        ),
        ratio=setting(float, 0.5, low=0.0, high=10.0, doc="tone RMS / RMS of the domain's healthy signal"),
    )
    log_scale = frozenset({"frequency"})
    # The record's line and its least-squares level pin frequency and level to a few tenths of a
    # percent of their ranges (the level is read against the band-limited record's RMS, which lacks
    # the orders above its passband: 10 % high on a 0.39 x 4096 record): the search refines from
    # there on this scale (gearlab.gap.diagnose._fit_search).
    guess_step = 0.002

    def apply_signal(self, x, params, ctx):
        f = params["frequency"]
        if f >= ctx.fs / 2:
            raise GearlabInputError(
                f"effect 'interference_tone': frequency {f:g} Hz is above the Nyquist frequency {ctx.fs / 2:g} Hz "
                f"of the record (4096 samples per revolution at {ctx.speed_hz:g} Hz)"
            )
        record = np.asarray(x, dtype=float)
        amplitude = np.sqrt(2.0) * params["ratio"] * ctx.reference_rms
        return record + amplitude * _wave(f, ctx, record.shape)

    def guesses(self, target_X, speed_hz):
        """The strongest line of the target that is not shaft-synchronous: the TSA (mean
        revolution) removed, the mean power spectrum of the residual revolutions, zero-padded
        8 times (a Hann window: its peak lies within a few percent of a bin of the line); the
        ratio from the line's power against the rest of the signal (which holds the target's
        noise too: under heavy noise the ratio comes out low, and the search refines it)."""
        X = np.asarray(target_X, dtype=float)
        residual = X - X.mean(axis=0)
        n, pad = X.shape[1], 8
        window = np.hanning(n)
        power = np.mean(np.abs(np.fft.rfft(residual * window, n=pad * n, axis=1)) ** 2, axis=0)
        f = np.fft.rfftfreq(pad * n, d=1.0 / (n * speed_hz))
        keep = (f >= FREQUENCY.low) & (f <= min(FREQUENCY.high, 0.45 * n * speed_hz))
        if not keep.any():
            return []
        peak = float(f[keep][np.argmax(power[keep])])
        # The line's own power: least squares of each residual revolution on sin/cos at the peak.
        t = np.arange(n) / (n * speed_hz)
        basis = np.stack([np.sin(2 * np.pi * peak * t), np.cos(2 * np.pi * peak * t)], axis=1)
        coef, *_ = np.linalg.lstsq(basis, residual.T, rcond=None)
        tone = float(np.mean(np.sum((basis @ coef) ** 2, axis=0)) / n)
        rest = max(float(np.mean(X**2)) - tone, 1e-300)
        ratio = min(float(np.sqrt(tone / rest)), RATIO.high)
        guesses = [{"frequency": peak, "ratio": ratio}]
        # The rows read as one record, one revolution after another: when they are consecutive
        # revolutions of a measured record, its spectrum resolves speed / rows, so a line below one
        # shaft order (37.3 Hz at 40 Hz) is found where one revolution cannot place it, and a line
        # between higher orders to a fraction of a hertz -- which a search against consecutive rows
        # needs (their tone runs on, its line is one record bin wide: 1037 Hz fitted from the
        # one-revolution peak stayed 5 Hz off and left a gap). When they are independent
        # revolutions the peak only blurs, and the search keeps the better guess.
        record = residual.reshape(-1)
        fs = n * speed_hz
        tapered = record * np.hanning(record.size)
        long = np.abs(np.fft.rfft(tapered, n=2 * record.size)) ** 2
        fl = np.fft.rfftfreq(2 * record.size, d=1.0 / fs)
        keep = (fl >= FREQUENCY.low) & (fl <= min(FREQUENCY.high, 0.45 * fs))
        fine = float(fl[keep][np.argmax(long[keep])])
        # Zoomed to 1/ZOOM of a record bin around that peak: a search against consecutive rows
        # scores a line below one order by the record's own lines (gearlab.gap.views.record_view),
        # whose valley is a few tenths of a percent of the frequency wide (a 7.3 Hz tone started
        # from the half-bin grid, 0.25 Hz, ended 4.5 % off); the level then from the whole record's
        # least squares at that frequency (one revolution holds a fifth of such a line's cycle).
        from scipy.signal import zoom_fft  # here, not at the top: start-up time (every command loads plugins)

        bin_hz = fs / record.size
        lo, hi = max(fine - bin_hz, FREQUENCY.low), fine + bin_hz
        zoom = np.abs(zoom_fft(tapered, [lo, hi], m=ZOOM, fs=fs, endpoint=True)) ** 2
        fine = float(np.linspace(lo, hi, ZOOM)[np.argmax(zoom)])
        t = np.arange(record.size) / fs
        basis = np.stack([np.sin(2 * np.pi * fine * t), np.cos(2 * np.pi * fine * t)], axis=1)
        coef, *_ = np.linalg.lstsq(basis, record, rcond=None)
        line = 0.5 * float(coef @ coef)  # the line's mean square
        level = min(float(np.sqrt(line / max(float(np.mean(X**2)) - line, 1e-300))), RATIO.high)
        # Independent rows (each its own tone phase) hold no coherent line across the record: their
        # record level reads about 1/sqrt(rows) of the line's, and the one-revolution level stands.
        if level >= 0.5 * ratio:
            ratio = level
        if abs(fine - peak) > 1e-4 * peak:
            guesses.append({"frequency": fine, "ratio": ratio})
        # The level is read against the target's whole RMS, the effect's against the healthy
        # reference's, which other effects (a sensor resonance lifting the mesh harmonics) move: at
        # the right frequency a level 40 % off scored like a tone at twice the frequency (a 179 Hz
        # tone next to a 4.9 kHz resonance came back at 357 Hz). The record's frequency is tried at
        # levels RATIO_LADDER times the reading too.
        guesses += [{"frequency": fine, "ratio": min(ratio * k, RATIO.high)} for k in RATIO_LADDER if ratio * k > 0]
        return guesses


def _wave(f: float, ctx, shape: tuple) -> np.ndarray:
    """sin(2 pi f t) at the times of a record of *shape* (read-only), kept where the context's times are
    SignalContext's (t0 + i / fs): a gap search scores one record at one frequency at many levels
    (tests/test_gap_diagnose.py: 4,837 calls, 421 distinct waves; a 64 x 4096 record's sine is 5.5 ms), and
    the level multiplies the kept wave, so every value is as computed anew."""
    if type(ctx).time is not SignalContext.time:  # another time base: its own times, not kept
        return np.sin(2 * np.pi * f * ctx.time(int(np.prod(shape))).reshape(shape))
    # A row's waves apart from a record's: a search scores rows of one revolution each with its own t0 between
    # its records' levels, and one cache of 8 kept neither (4,837 misses in 4,837 calls, 285 of them 64 x 4096
    # records' 5.5 ms sines); apart, 396 rows' and 27 records' waves are made (the distinct ones: 396 and 25).
    return (_row_sine if int(np.prod(shape)) <= ROW_SAMPLES else _sine)(f, ctx.t0, ctx.fs, shape)


ROW_SAMPLES = 8192  # a wave of at most this many samples is a row's (kept 256: 16 MB at most)


def _made_sine(f: float, t0: float, fs: float, shape: tuple) -> np.ndarray:
    t = t0 + np.arange(int(np.prod(shape))) / fs  # SignalContext.time's
    wave = np.sin(2 * np.pi * f * t.reshape(shape))
    wave.flags.writeable = False
    return wave


_sine = lru_cache(maxsize=8)(_made_sine)  # a 64 x 4096 record's wave: 2 MB
_row_sine = lru_cache(maxsize=256)(_made_sine)


FREQUENCY, RATIO = (setting_of(InterferenceTone.params, name) for name in ("frequency", "ratio"))


@hookimpl
def gearlab_effects():
    return [InterferenceTone()]
