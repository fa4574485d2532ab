"""The adapter contract of the domain-adaptation methods (thesis ch. 5).

An adapter plugin is an :class:`Adapter` registered through the ``gearlab`` entry-point
group (hook ``gearlab_adapters``). The trainer asks it for

- ``extra_modules(latent_dim)`` — trainable modules beyond the network (DANN's domain
  classifier), optimised together with the network;
- ``domain_loss(z_s, z_t, modules, lam)`` — the term added to the classification loss on
  the latent features of a joint source/target batch (eq. 5.12, 5.18), λ and any gradient
  reversal already applied;
- ``discrepancy(z_s, z_t, modules)`` — the domain discrepancy measure used for stopping
  (Table 5.3: "domain discrepancy measure minimum"), a plain float;
- ``domain_terms(z_s, z_t, modules, lam)`` — the two above from one computation, when the
  discrepancy is the loss's own measure before λ (CORAL, MMD²); by default the loss and None,
  and the trainer asks ``discrepancy`` after the step;
- ``lambda_schedule(epoch)`` — λ for an epoch of joint training (Table 5.3);
- ``trainable(network)`` — the network parameters the adapter's training step updates.

``calibrated`` adapters are primed on the full source set and then adapted (thesis 5.4.2);
``train_on`` says which data the (post-priming) training step sees: "source", "target" or
"joint" (40 source + 40 target samples a batch); a method that trains no network is a
detector, another kind of plugin (gearlab.learn.detector_contract);
``optimizer`` is "adam" (TensorFlow defaults) for the uncalibrated baselines and "sgd"
(lr 0.003) for the calibrated methods.

Every method taking ``params`` accepts ``None`` (the schema defaults) or a mapping as
returned by :meth:`Adapter.resolve`.

This module does not import torch: the registry imports every adapter plugin on every
``gearlab`` command, and torch alone takes seconds to import. The shared torch losses
(MMD², CORAL, gradient reversal) live in :mod:`gearlab.learn.losses`; the base class and
the plugins import torch inside the methods that use it, which only run while training.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

from gearlab.errors import GearlabInputError, did_you_mean
from gearlab.settings import NoParams, declared, plugin_description, resolve_params, setting

if TYPE_CHECKING:  # for the annotations only; see the module docstring
    import torch
    from torch import nn

SUPERVISIONS = ("unsupervised", "supervised")
TRAIN_ON = ("source", "target", "joint")

# Table 5.3: λ starts at 0 and grows by 0.05 every 25 epochs up to 1.
LAMBDA_STEP = 0.05
LAMBDA_EVERY = 25
LAMBDA_MAX = 1.0


def schedule_settings() -> dict:
    """The λ schedule's parameters (Table 5.3), after a domain-loss adapter's own:
    ``params = parameters(own=setting(...), **schedule_settings())``."""
    return {
        "lambda_step": setting(
            float, LAMBDA_STEP, low=0.0, high=1.0, doc="increase of the domain-loss weight λ at each step (Table 5.3)"
        ),
        "lambda_every": setting(
            int, LAMBDA_EVERY, low=1, high=10_000, doc="epochs of joint training between λ steps (Table 5.3)"
        ),
        "lambda_max": setting(float, LAMBDA_MAX, low=0.0, high=10.0, doc="largest domain-loss weight λ (Table 5.3)"),
    }


# ----------------------------------------------------------------------------- schedule


def lambda_schedule(
    epoch: int, step: float = LAMBDA_STEP, every: int = LAMBDA_EVERY, maximum: float = LAMBDA_MAX
) -> float:
    """λ after *epoch* epochs of joint training: 0, then +*step* every *every* epochs, capped at *maximum*."""
    if epoch < 0:
        raise ValueError(f"epoch must be >= 0, got {epoch}")
    return float(min(maximum, round(step * (int(epoch) // int(every)), 12)))


# ----------------------------------------------------------------------------- contract


class MethodPlugin:
    """What every method a scenario names has, an adapter (below) or a detector
    (gearlab.learn.detector_contract): a name, a parameter schema, the supervision it offers."""

    kind: str = ""  # its registry kind, for messages
    name: str = ""
    doc: str = ""
    params: type = NoParams  # a settings dataclass (gearlab.settings)
    supervision: tuple[str, ...] = SUPERVISIONS
    choices: dict[str, tuple[str, ...]] = {}  # parameter -> names of its codes 0, 1, ... (scenarios may give either)

    def coerce(self, given: Mapping[str, object], where: str) -> dict:
        """Turn scenario values that are not numbers (the names of ``choices``) into their codes."""
        values = dict(given)
        for key, names in self.choices.items():
            value = values.get(key)
            if isinstance(value, str) and not value.strip().lstrip("+-").isdigit():
                name = value.strip().lower()
                if name not in names:
                    raise GearlabInputError(
                        f"{where}, parameter '{key}': unknown value '{value}'"
                        f"{did_you_mean(name, names)}; known: {', '.join(names)}"
                    )
                values[key] = names.index(name)
        return values

    def resolve(self, given: Mapping[str, object] | None = None, where: str = "") -> dict:
        """Defaults filled, units parsed, names and bounds checked (GearlabInputError otherwise)."""
        where = where or f"{self.kind} '{self.name}'"
        return resolve_params(self.params, self.coerce(given or {}, where), where)

    def values(self, params: Mapping[str, object] | None) -> dict:
        values = {name: default for name, (_, default) in declared(self.params).items()}
        values.update(params or {})
        return values

    def named(self, params: Mapping[str, object] | None) -> dict:
        """:meth:`values` with each ``choices`` parameter's code turned into its name."""
        values = self.values(params)
        for key, names in self.choices.items():
            values[key] = names[int(values[key])]
        return values

    def __repr__(self) -> str:
        return f"<{self.kind} {self.name}>"


class Adapter(MethodPlugin):
    """Base of every adapter plugin; the defaults are those of a method without domain loss."""

    kind = "adapter"
    calibrated: bool = False
    train_on: str = "source"
    optimizer: str = "adam"

    # ---- training

    def extra_modules(self, latent_dim: int, params: Mapping | None = None) -> nn.ModuleDict:
        """Trainable modules beyond the network (optimised with it); none by default."""
        from torch import nn

        return nn.ModuleDict()

    def domain_loss(
        self,
        z_s: torch.Tensor,
        z_t: torch.Tensor,
        modules: nn.ModuleDict,
        lam: float,
        params: Mapping | None = None,
    ) -> torch.Tensor:
        """The term added to the classification loss; zero for a method without domain loss."""
        return z_s.new_zeros(())

    def domain_terms(
        self,
        z_s: torch.Tensor,
        z_t: torch.Tensor,
        modules: nn.ModuleDict,
        lam: float,
        params: Mapping | None = None,
    ) -> tuple[torch.Tensor, float | None]:
        """(domain_loss, its batch's discrepancy or None). None: the trainer measures
        :meth:`discrepancy` after the optimiser's step (DANN's depends on the stepped domain
        classifier). An adapter whose discrepancy is its loss before λ returns it here, so the
        batch's measure is computed once: the same number as discrepancy() (the same operations
        on the same latent values), a fifteenth of an MMD unit's training time less."""
        return self.domain_loss(z_s, z_t, modules, lam, params), None

    def discrepancy(
        self, z_s: torch.Tensor, z_t: torch.Tensor, modules: nn.ModuleDict, params: Mapping | None = None
    ) -> float:
        """Domain discrepancy of two latent batches (lower is better); MMD² unless the method has its own."""
        import torch

        from gearlab.learn.losses import mmd2

        with torch.no_grad():
            return float(mmd2(z_s, z_t))

    def lambda_schedule(self, epoch: int, params: Mapping | None = None) -> float:
        """λ after *epoch* epochs of joint training (after priming); Table 5.3 by default."""
        v = self.values(params)
        return lambda_schedule(
            epoch,
            step=float(v.get("lambda_step", LAMBDA_STEP)),
            every=int(v.get("lambda_every", LAMBDA_EVERY)),
            maximum=float(v.get("lambda_max", LAMBDA_MAX)),
        )

    def trainable(self, network: nn.Module, params: Mapping | None = None) -> list[nn.Parameter]:
        """The network parameters this method's training step updates; all of them by default."""
        return list(network.parameters())

    # ---- description

    def describe(self) -> dict:
        return plugin_description(
            self,
            calibrated=self.calibrated,
            supervision=list(self.supervision),
            train_on=self.train_on,
            optimizer=self.optimizer,
        )


__all__ = [
    "LAMBDA_EVERY",
    "LAMBDA_MAX",
    "LAMBDA_STEP",
    "SUPERVISIONS",
    "TRAIN_ON",
    "Adapter",
    "MethodPlugin",
    "lambda_schedule",
    "schedule_settings",
]
