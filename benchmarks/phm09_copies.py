"""Issue 19, which shaft: why the PHM 2009 chip is not put on the input shaft.

On a rig without a hunting tooth (96 = 3 x 32) a chipped pinion tooth meets the same three teeth of
the idler's gear, so in the idler's TSA (three input revolutions) it appears in all three copies of
the input revolution; pinion_sync takes that pattern, scaled by a smooth non-reversing modulation of
the idler's turn (an eccentric idler), for the pinion's, and what the copies hold beyond it
(indicators.modulated_residual) for a tooth of the idler. For a detection scenario (the records,
conditions, alignment and history as the kind reads them; no training) this prints, per condition and
record, at the tooth window k where the record's input TSA has its largest localised excess over the
history (the chip's window in spur2):

* e0: the input part's excess (share of the TSA's mean window energy), median over the record's
  TSA30 units; r: the idler residual's excess over the history as a fraction of what an idler tooth
  with that input image would leave (0 a pinion tooth, 1 an idler tooth; pinion_sync counts the
  image as explained from 0.5);
* of the whole record: each copy's synchronous energy in window k (share), the free gains of the
  copies against their mean, whether they lie in the non-reversing cone (its distance, 0 inside),
  the copies' synchronous correlations (1 when the copies have one shape, as a modulated pinion
  tooth's), and the residual per copy, beside the history records' in the same window.

The test labels are read only to print them.

    python benchmarks/phm09_copies.py scenarios/phm09_chip.toml [--swap-takes]

About 30 s.
"""

from __future__ import annotations

import numpy as np
from phm09_localised import command_line

from gearlab.kinds import record_effects
from gearlab.kinds.detection import read_target
from gearlab.signals.indicators import (
    modulation_distance,
    shaft_parts,
    single_phase_residual,
    window_gram,
    window_reference,
)

BLOCK, STRIDE, Q = 30, 3, 3


def copies(gram: np.ndarray, k: int, q: int = Q) -> dict:
    """The whole record's q phase TSAs in window k: synchronous energies, free gains, cone distance,
    correlations and the residual per copy, all as shares of the record TSA's mean window energy."""
    b = gram.shape[-1]
    member = (np.arange(b)[None, :] % q == np.arange(q)[:, None]).astype(np.float64)
    count = member.sum(axis=1)
    off = gram[k] * (1.0 - np.eye(b))
    M = member @ off @ member.T / (np.outer(count, count) - np.diag(count))
    norm = gram.sum(axis=(1, 2)).mean() / b**2
    cp, pp = M.mean(axis=1), M.mean()
    free = cp / pp
    own = np.diag(M)
    rho = M / np.sqrt(np.outer(np.abs(own), np.abs(own)))
    left = (own.sum() - np.sum(cp**2) / pp + pp * modulation_distance(free[None])[0]) / q
    return {
        "energy": own / norm,
        "gains": free,
        "cone": float(modulation_distance(free[None])[0]),
        "rho": [rho[i, j] for i in range(q) for j in range(i + 1, q)],
        "residual": left / norm,
    }


def main() -> None:
    args, spec, target, labels = command_line(__doc__.splitlines()[0])
    c = spec["classical"]
    orders, shafts = c["mesh_orders"], [q for _, q in c["shafts"]]
    teeth, f = orders[0], single_phase_residual(Q)
    conditions = read_target(target, spec["blocks"], lambda e: None)
    print(
        "| condition | record | role, label | window k | e0 (TSA30) | r (TSA30) | copies' energy | free gains "
        "(cone distance) | copies' correlation | residual per copy (history mean) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, cond in conditions.items():
        grams = {f_.path: window_gram(r, teeth, orders) for role in ("history", "test") for f_, r in cond[role]}
        hist = [
            shaft_parts(r, BLOCK, STRIDE, teeth, orders, shafts, gram=grams[f_.path]).reshape(
                -1, (1 + len(shafts)) * teeth
            )
            for f_, r in cond["history"]
        ]
        dofs = [record_effects.overlap_dof(len(h), BLOCK, STRIDE) for h in hist]
        mean = window_reference(hist, dofs)[0].reshape(1 + len(shafts), teeth)
        hist_residual = {}
        for f_, _ in cond["history"]:
            g = grams[f_.path]
            hist_residual[f_.path] = [copies(g, k)["residual"] for k in range(teeth)]
        for role in ("history", "test"):
            for f_, r in cond[role]:
                g = grams[f_.path]
                parts = shaft_parts(r, BLOCK, BLOCK, teeth, orders, shafts, gram=g)
                excess = parts - mean
                k = int(np.argmax(np.median(excess[:, 0], axis=0)))
                e0 = np.median(excess[:, 0, k])
                ratio = np.median(excess[:, 1, k] / (f * Q * Q * excess[:, 0, k]))
                cc = copies(g, k)
                hr = np.mean([v[k] for v in hist_residual.values()])
                energy, gains = ", ".join(f"{x:.1f}" for x in cc["energy"]), ", ".join(f"{x:.2f}" for x in cc["gains"])
                rho = ", ".join(f"{x:.2f}" for x in cc["rho"])
                print(
                    f"| {name} | {f_.path.split('/')[-1]} | {role}, {labels[f_.path]} | {k} | {e0:.2f} | {ratio:.2f} | "
                    f"{energy} | {gains} ({cc['cone']:.2f}) | {rho} | {cc['residual']:.2f} ({hr:.2f}) |"
                )


if __name__ == "__main__":
    main()
