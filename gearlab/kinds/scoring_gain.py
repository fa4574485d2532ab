"""A run's [target] gain carried by gearlab score to a file of a format the run read none of, said where it changes
what the gain means: a WAV's unit is its full scale (gain = "10 V": one file unit is 10 V), while a text, npz, HDF5
or MAT file's unit is the value written (in volts: 1 V). The [target]'s keys apply to such a file
(detection_scoring.remembered), so a run of int16 WAVs at a 10 V full scale read next week's take, exported as
text in volts, 10 x too loud, and said only 'level 10 x its history's (g and m/s² mixed up? ...)'."""

from __future__ import annotations

FULL_SCALE_FORMATS = (".wav",)  # a file unit that is the format's full scale, not the value written


def full_scale_elsewhere(meta: dict, given: dict | None, fmt: str) -> tuple[str, ...]:
    """The warning for a file of format *fmt* (detection_scoring.file_format) read with the [target]'s gain where
    every file the run read was a WAV and *file* is none, or the other way round, as a take's flaws (said with its
    rows); () otherwise (a gain given with --key, a format the run read, no gain)."""
    kept = meta.get("file_keys") or {}
    read = set(kept.get("formats", {})) | set(kept.get("sets", {}))
    gain = meta["target"].get("gain")
    if not read or fmt in read or "gain" in (given or {}) or not isinstance(gain, (int, float)):
        return ()
    full = {f in FULL_SCALE_FORMATS for f in read}
    if len(full) != 1 or (fmt in FULL_SCALE_FORMATS) in full:
        return ()
    if True in full:
        meant, here = "the full scale of the run's WAV files", f"a {fmt} file's unit is the value written"
        fix = "values in volts: --key gain= (none); counts: --key gain=<volts per count>"
    else:
        meant, here = f"volts per unit of the run's {', '.join(sorted(read))} files", "a WAV's unit is its full scale"
        fix = "--key gain=<its full scale, e.g. '10 V'>"
    return (
        f"the [target]'s gain '{gain:g} V' ({meant}) multiplies its values, but {here}; check its values: line ({fix})",
    )
