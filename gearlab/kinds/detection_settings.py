"""The detection kind's settings and what its build() gives (kinds.detection): the [corrected],
[target], [classical] and [detection] tables as settings dataclasses (gearlab.settings), and
`Spec`, the checked scenario the kind's modules read (run, scoring, tables, classical indicators)."""

from __future__ import annotations

from dataclasses import MISSING, dataclass

from ..data.spec import POINTS, DatasetSpec
from ..learn.config import RECIPE
from ..learn.protocol import Protocol
from ..parts.measured import Target
from ..settings import setting
from ..signals.indicators import DEFAULT_INDICATORS, INDICATORS
from .common import measured

SOURCE_SPEEDS = ("records", "source")
INPUTS = ("difference", "revolution")
THRESHOLDS = ("records", "pooled")
# How a network's history scores are made: "all" -- trained on every history record and scoring them
# (in-sample); "crossed" -- one training per history record left out, which scores it (a new record's
# scores, as the test records' are)
HISTORY_FITS = ("all", "crossed")
CORRECTED_HISTORY = ("revolution", "tsa")
MAX_SEEDS = 20
MAX_DRAWS = 64

# One threshold rule and one false-alarm rate in a detection scenario, [detection]'s: every method's
# threshold is fixed on the history's units, which re-fixes a calibrated network's or a detector's
# own (a shift of all its scores), so [protocol] has no threshold keys here; the models' own keep
# gearlab's recipe (a history threshold at 1 %).
UNIT_THRESHOLD = {"threshold": RECIPE.threshold, "false_alarm": RECIPE.false_alarm}


@dataclass(frozen=True, kw_only=True)
class Corrected:
    """[corrected]: the corrected source (the [source] with the effects a gap diagnosis found, its
    gearbox description with the values it fitted)."""

    effects: list = setting(list, [], doc="effects added to the [source]'s: the corrected simulator (none: plain only)")
    gearbox: str = setting(
        str,
        "",
        doc="a gearbox description in place of the [source]'s in the corrected simulator: a gap run's "
        "gearbox_corrected.toml (its fitted values); the same gears, relative to the scenario",
    )
    label: str = setting(str, "corrected", doc="the corrected source's name in the method rows")
    tsa: int = setting(
        int,
        0,
        low=0,
        high=1000,
        doc="a corrected sample is the TSA of this many simulated revolutions, each with its own "
        "noise (the revolutions of a record-level unit); 0: one revolution",
    )
    draws: int = setting(
        int,
        1,
        low=1,
        high=MAX_DRAWS,
        doc="noise draws of each corrected sample; a network trains on one of them at random per "
        "batch row, so it cannot learn the noise of one draw by heart (docs/real_data.md)",
    )
    history_units: str = setting(
        str,
        "revolution",
        choices=CORRECTED_HISTORY,
        doc="what the corrected source's methods see of the history in training: 'revolution' (the "
        "history revolutions, as the plain source's) or 'tsa' (the history's TSAs of `tsa` "
        "revolutions, sliding as its units are: the target at the corrected sample's averaging)",
    )


@dataclass(frozen=True, kw_only=True)
class TargetRecords:
    """[target]: the measured records, history and test, with every kind's measured-data keys."""

    vibration: int | str = measured("vibration")
    tacho: int | str = measured("tacho")
    tacho_shaft: str = measured("tacho_shaft")
    pulses_per_rev: int = measured("pulses_per_rev")
    speed: float | str | None = measured("speed")
    gearbox: str = measured("gearbox")
    sensitivity: float | str | None = measured("sensitivity")
    unit: str = measured("unit")
    gain: float | str | None = measured("gain")
    fs: float | str | None = measured("fs")
    takes: str = measured("takes")
    transient: str = measured("transient", "none")
    positive: str = setting(str, "fault", doc="the label of records with the fault to detect; every other is negative")
    files: list = measured("files", MISSING)


@dataclass(frozen=True, kw_only=True)
class Classical:
    """[classical]: the classical indicators of the TSA. In the Spec its lists are tuples and
    `shafts` its (name, period) pairs."""

    indicators: tuple[str, ...] = setting(
        list, list(DEFAULT_INDICATORS), doc=f"classical indicators of the TSA: {', '.join(INDICATORS)}"
    )
    mesh_orders: tuple[int, ...] = setting(
        list,
        [],
        doc="mesh orders of the TSA's shaft (default: the source pinion's teeth); the first is the "
        "tooth count of the gear on that shaft (the localised indicators' windows)",
    )
    shaft_orders: int = setting(int, 2, low=0, high=100, doc="low shaft orders removed with the mesh harmonics")
    sidebands: int = setting(int, 1, low=0, high=100, doc="sidebands either side of each mesh harmonic (FM4)")
    slow_shafts: tuple[int, ...] = setting(
        list,
        [],
        doc="periods, in whole input revolutions, of the other shafts whose localised damage "
        "tooth_sync is to tell from the input pinion's (a shaft turning q times slower, q whole, "
        "brings a tooth back to one input angle every q revolutions; the PHM rig: [3, 5])",
    )
    shafts: tuple[tuple[str, int], ...] = setting(
        dict,
        {},
        doc="the other shafts a localised fault may turn with, {name = period in whole input "
        "revolutions} (the PHM rig: {idler = 3, output = 5}): pinion_sync calls a pinion fault "
        "only for localised content of the input TSA that no tooth of these shafts explains (what "
        "each shaft's TSA holds beyond the input TSA's copies under a smooth modulation of its turn)",
    )


@dataclass(frozen=True, kw_only=True)
class Detection:
    """[detection]: the record-level units (in the Spec, `blocks` a tuple), the one threshold rule
    and false-alarm rate."""

    blocks: tuple[int, ...] = setting(list, [10, 30], doc="revolutions per record-level TSA unit")
    false_alarm: float = setting(
        float, 0.01, low=1e-6, high=0.5, doc="share of healthy history units above the threshold"
    )
    input: str = setting(
        str,
        "difference",
        choices=INPUTS,
        doc="what the learned methods see: 'difference' (revolution or TSA less its "
        "shaft and mesh orders, as FM4's) or 'revolution' (as it is)",
    )
    points: int = setting(
        int,
        POINTS,
        low=64,
        high=POINTS,
        doc="samples per revolution the learned methods see: the order spectrum of what they see cut "
        f"below points / 2 ({POINTS}, the records' grid: all of it)",
    )
    threshold: str = setting(
        str,
        "records",
        choices=THRESHOLDS,
        doc="'records': predictive quantile for a new record's unit (record effect + within-record "
        "spread, one-way random effects); 'pooled': Gumbel quantile of the pooled history units",
    )
    history_fit: str = setting(
        str,
        "all",
        choices=HISTORY_FITS,
        doc="how a network's history scores are made: 'all' (trained on every history record, "
        "which it then scores) or 'crossed' (one training per history record left out of its "
        "training rows; that record's units are scored by it, the test units by all of them)",
    )
    seeds: int = setting(
        int,
        1,
        low=1,
        high=MAX_SEEDS,
        doc="trainings per network method and condition; more than 1: the median of their history-standardised scores",
    )
    source_speed: str = setting(
        str,
        "records",
        choices=SOURCE_SPEEDS,
        doc="'records': the source simulated at each condition's history speed "
        "(to 0.001 Hz; to 1 Hz from a tacho); 'source': at the [source]'s own speed",
    )


def stored_classical(stored: dict) -> Classical:
    """The [classical] settings a finished run stored for `gearlab score` (its tuples as lists)."""
    return Classical(
        indicators=tuple(stored["indicators"]),
        mesh_orders=tuple(stored["mesh_orders"]),
        shaft_orders=stored["shaft_orders"],
        sidebands=stored["sidebands"],
        slow_shafts=tuple(stored["slow_shafts"]),
        shafts=tuple((name, q) for name, q in stored["shafts"]),
    )


@dataclass(frozen=True)
class Spec:
    """What the detection kind's build() checked: the sources, the measured target, the protocol
    (one training per method and condition) and the typed [classical] and [detection] tables."""

    source: DatasetSpec
    corrected: DatasetSpec | None  # the [source] with the [corrected] effects; None: no effects given
    corrected_label: str
    # the corrected source's history training rows: TSAs of its `tsa` revolutions, or 0: revolutions
    corrected_history: int
    corrected_draws: int  # noise draws of each corrected sample
    target: Target
    protocol: Protocol
    classical: Classical
    detection: Detection
