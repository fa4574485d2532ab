"""The learning settings a scenario declares, without torch: the [network] table and the
calibration keys of [protocol].

They live apart from the networks and the calibrated model (gearlab.learn.networks,
gearlab.learn.calibration, which define torch modules and re-export these names) so that
checking a scenario (`gearlab validate`, the TUI's scenario list) loads no torch.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import GearlabInputError, did_you_mean
from ..settings import declared, in_bounds, setting
from .history import NOISE_LAWS
from .path import PATHS

DEFAULT_NETWORK = "shapes"
DEFAULT_DROPOUT = 0.005  # Han et al. (2019a), thesis 3.1.6 and Table 5.3
DEFAULT_LENGTH = 4096  # samples per rotation (thesis 3.1.6)
# the names of gearlab.learn.networks.NETWORKS, in its order (tests/test_startup.py checks them)
NETWORK_NAMES = ("cnn3", "fast", "burst", "shapes")


def _network_name(name: str, where: str) -> str:
    if name not in NETWORK_NAMES:
        raise GearlabInputError(
            f"{where}: unknown network '{name}'{did_you_mean(name, list(NETWORK_NAMES))}; "
            f"known networks: {', '.join(NETWORK_NAMES)}"
        )
    return name


@dataclass(frozen=True)
class NetworkSettings:
    """A scenario's [network] table (transfer, detection, gap, noise_study; a kind may give
    other defaults, gearlab.scenario.keys_of)."""

    name: str = setting(str, DEFAULT_NETWORK, check=_network_name, doc=f"network: {', '.join(NETWORK_NAMES)}")
    dropout: float = setting(float, DEFAULT_DROPOUT, low=0.0, high=0.95, doc="dropout rate (Table 5.3: 0.5 %)")


# The calibration of a calibrated method (gearlab.learn.calibration explains each setting)
STARTS = ("random", "faults")
SOURCE_NOISE = ("off", "auto", *NOISE_LAWS)
ALIGNMENTS = ("marginal", "healthy")
THRESHOLDS = ("argmax", "history")


@dataclass(frozen=True)
class Calibration:
    """The settings gearlab.learn.calibration describes, declared once (the ``[protocol]`` keys of the kinds that train
    derive from these fields); the defaults are the thesis's recipe, :data:`RECIPE` gearlab's."""

    residual: bool = setting(bool, False, doc="input = revolution minus its domain's healthy reference")
    path: str = setting(str, "gain", choices=PATHS, doc="source residuals to the target's units (with residual)")
    start: str = setting(str, "random", choices=STARTS, doc="priming: the filter bank's start (faults: matched)")
    source_noise: str = setting(str, "off", choices=SOURCE_NOISE, doc="fresh sensor noise on source batches")
    alignment: str = setting(str, "marginal", choices=ALIGNMENTS, doc="what the domain loss aligns")
    threshold: str = setting(str, "argmax", choices=THRESHOLDS, doc="fault call")
    false_alarm: float = setting(
        float, 0.01, low=1e-6, high=0.49, doc="share of the history above a 'history' threshold"
    )

    def check(self, where: str) -> None:
        """Refuse a value outside its declaration (a Calibration made in code, not from a scenario)."""
        for name, (meta, _) in declared(type(self)).items():
            in_bounds(meta, getattr(self, name), f"{where}: [protocol] key '{name}'")


THESIS = Calibration()
RECIPE = Calibration(
    residual=True, path="fir", start="faults", source_noise="auto", alignment="healthy", threshold="history"
)


def shortest_length(name: str) -> int:
    """The fewest samples per revolution network *name* takes (gearlab.learn.networks refuses
    fewer when it builds one; tests/test_startup.py checks the two agree), known without torch."""
    return {"cnn3": 64 + 32 + 16 + 1, "fast": 64, "burst": 2 * 33, "shapes": 1}[name]


def check_length(name: str, length: int) -> None:
    """Refuse revolutions of *length* samples for network *name*, as building it would."""
    shortest = shortest_length(name)
    if length < shortest:
        raise GearlabInputError(f"network '{name}': signals must have at least {shortest} samples, got {length}")
