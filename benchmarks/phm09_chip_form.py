"""Issue 19, sixteenth round: is the simulated chip too small, or of the wrong form?

The corrected networks rank the simulated chips well under their source's bound, and what they
call on the records does not follow what they learned of the simulator. Two readings: the
simulated chip is too weak under the fitted noise to be learned, or it is learned and is not what
the real chip looks like. This benchmark measures both, for a detection scenario with a
`[corrected]` source:

* ``--factors A ...`` (the size): every chip of the corrected source multiplied by A, exactly: the
  corrected sample is its noise-free signal (``detection.noise_free_twin``) plus its noise draws,
  and A - 1 times its chip response (the twin's chipped sample less the twin's healthy one) is
  added, the noise draws unchanged. The kind is run with ``--methods`` per factor (a run folder
  each, under OUT) and prints, per condition, the corrected rows' source AUC (training data only,
  beside the source's bound, which the factor raises too) and their record30 AUC and detected /
  false alarms % on the records.
* ``--path`` (a transfer path from the history): every chip response first passes the gain of the
  records' mesh harmonics over the simulator's, from the healthy history alone: at each multiple
  of 16 orders the median over the history records of ln |record| - ln |simulator| (their mean
  revolutions), a running median over 5 harmonics, 0 dB at orders up to 64, linear in between,
  zero phase (the mesh harmonics' phases do not follow a short filter:
  ``gearlab.learn.path.fit_path`` finds no path between these references and gives one gain);
  ``--path minimum``: the minimum-phase response of the same gain instead (causal: it rings after).
  The bound printed is the kind's: the likelihood ratio with the chip shapes as simulated, so with
  a factor or the gain it is a lower figure than the changed source's own bound.
* ``--form`` (reads test records, a diagnosis, no decision): the real chip's synchronous signature
  is the mean revolution of a chipped record less that of the record of the same take whose only
  difference is the chip (``--base-label``; on the PHM rig spur2 against spur3), as the learned
  methods see it; the control is a healthy-pinion record less the same base (spur1 against
  spur3). For each it prints where its energy lies over order bands, the same for the simulated
  chips (the largest step, as simulated and through ``--path``'s gain), and the best normalised
  correlation of any simulated chip (every tooth and step) with it over the eighth of the
  revolution holding most of that chip's energy: as simulated, through ``--path``'s zero-phase gain,
  and through the minimum-phase response of the same gain (a structure rings after an impact).
* ``--contact`` (the simulator alone): can a chip make the teeth lose contact and strike again? The
  stage-1 mesh deflection P u over the last of four revolutions at the scenario source's speed and
  load, healthy and with the source's fault at its largest step on tooth 1 (the integrator stepped
  one step at a time to read displacements, which a simulation does not keep).
* ``--fault KIND`` (every option): the source's chip replaced by another fault plugin at the same
  ladder steps, e.g. ``broken_tip`` (the seventeenth round).

The records' figures read the test labels (as the kind's table does); nothing here feeds a
decision of the shipped scenario.

    python benchmarks/phm09_chip_form.py scenarios/phm09_chip.toml OUT [--factors 4 16] [--path [minimum]]
        [--form] [--contact] [--fault broken_tip] [--methods source_only] [--seeds 3] [--swap-takes]

About 75 s per factor for ``source_only`` (both sources are trained: the plain rows are the shipped
ones, a check), 9 min for ``dann``, on this machine with two workers; ``--form`` about 1 min.
"""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path
from unittest import mock

import numpy as np
from phm09_localised import learned_parser, learned_scenario, run_detection

from gearlab.data.builder import whole_steps_rate
from gearlab.data.cache import load_or_build
from gearlab.dynamics.newmark import Simulator, _integrate_meshes
from gearlab.kinds import detection
from gearlab.physics.faults import place_fault
from gearlab.registry import get_registry

BANDS = ((3, 60), (60, 160), (160, 320), (320, 1024))  # shaft orders
STEP = 16  # the rig's mesh harmonics are multiples of the stage-2 mesh order


def twin(spec, cond):
    """The condition's corrected source spec and its noise-free twin (a dataset)."""
    source = detection.source_for(spec["corrected"], cond, spec["source_speed"])
    clean, _ = load_or_build(detection.noise_free_twin(source, spec["corrected_draws"]))
    return source, clean


def history_gain(clean, cond) -> np.ndarray:
    """|G| per order of a revolution (zero phase): the records' mesh harmonics over the simulator's."""
    n = clean.X.shape[-1]
    sim = np.abs(np.fft.rfft(clean.X[clean.fault == 0].astype(np.float64).mean(axis=0)))
    orders = np.arange(STEP, min(cond["max_order"], n // 2) + 1, STEP)
    ratio = np.median(
        [np.log(np.abs(np.fft.rfft(revs.mean(axis=0)))[orders] / sim[orders]) for _, revs in cond["history"]], axis=0
    )
    padded = np.pad(ratio, 2, mode="edge")
    smooth = np.array([np.median(padded[i : i + 5]) for i in range(len(ratio))])
    smooth -= np.median(smooth[orders <= 64])
    return np.exp(np.interp(np.arange(n // 2 + 1), orders, smooth))


def minimum_phase(gain: np.ndarray) -> np.ndarray:
    """The causal, minimum-phase response with the magnitude *gain* (per order of a revolution): the
    folded real cepstrum of ln |gain| (Oppenheim & Schafer, ch. 12). A structure's path rings after
    what strikes it; the zero-phase gain spreads a chip's response both ways in time."""
    n = 2 * (len(gain) - 1)
    cepstrum = np.fft.irfft(np.log(gain), n=n)
    folded = np.zeros(n)
    folded[0], folded[n // 2] = cepstrum[0], cepstrum[n // 2]
    folded[1 : n // 2] = 2 * cepstrum[1 : n // 2]
    return np.exp(np.fft.rfft(folded))


def through(gain: np.ndarray | None, x: np.ndarray) -> np.ndarray:
    if gain is None:
        return x
    return np.fft.irfft(np.fft.rfft(x, axis=-1) * gain, n=x.shape[-1], axis=-1)


def chip_responses(clean) -> np.ndarray:
    """Each twin sample less the twin's healthy revolution (zero for a healthy sample)."""
    X = clean.X.astype(np.float64)
    return X - X[clean.fault == 0].mean(axis=0)


def patched_split(factor: float, gains: dict):
    """detection.source_split with the corrected source's chips times *factor*, through its gain."""
    shipped = detection.source_split

    def split(source, protocol, draws=1):
        if draws == 1:
            return shipped(source, protocol, draws)
        clean, _ = load_or_build(detection.noise_free_twin(source.spec, draws))
        chip = chip_responses(clean) * (clean.reference[1] / source.reference[1])  # the source's units
        added = through(gains.get(source.spec.name), factor * chip) - chip
        X = source.X.reshape(len(clean), draws, -1) + added[:, None, :]
        return shipped(dataclasses.replace(source, X=X.reshape(source.X.shape).astype(np.float32)), protocol, draws)

    return split


def run_factor(scenario, out: Path, factor: float, gains: dict) -> Path:
    with mock.patch.object(detection, "source_split", patched_split(factor, gains)):
        return run_detection(scenario, out)


def print_factor(path: Path, factor: float) -> None:
    summary = json.loads((path / "summary.json").read_text())
    learned = {(r["condition"], r["method"]): r for r in summary.get("learned", [])}
    print(f"\nchips x {factor:g} ({path}):")
    print("| condition | row | source AUC (seeds) [bound] | record30 AUC (seeds), det / FA |")
    print("|---|---|---|---|")
    for r in summary["rows"]:
        if r["unit"] != "record30" or "(" not in r["method"] or (r["condition"], r["method"]) not in learned:
            continue
        s = learned[(r["condition"], r["method"])]
        part = s.get("part_source_auc") or [s["source_auc"]]
        members = [a for a in r.get("member_auc") or [] if a is not None]
        spread = f" ({min(members):.2f}-{max(members):.2f})" if members else ""
        print(
            f"| {r['condition']} | {r['method']} | {s['source_auc']:.2f} ({min(part):.2f}-{max(part):.2f}) "
            f"[{s['source_bound']:.2f}] | {r['auc']:.2f}{spread}, {r['detection']:.0f} / {r['false_alarm']:.0f} |"
        )


def shares(x: np.ndarray) -> str:
    """Energy % per order band of *x*, or of its rows together."""
    power = (np.abs(np.fft.rfft(x)) ** 2).reshape(-1, x.shape[-1] // 2 + 1).sum(axis=0)
    total = power[BANDS[0][0] :].sum()
    return " / ".join(f"{power[a:b].sum() / total * 100:.0f}" for a, b in BANDS)


def best_local(chips: np.ndarray, tooth, step, x: np.ndarray) -> str:
    """The simulated chip that best matches *x* over the eighth of the revolution holding most of its energy."""
    n, w = len(x), len(x) // 8
    best = (0.0, 0)
    for i in np.flatnonzero(step > 0):
        energy = np.convolve(np.r_[chips[i] ** 2, chips[i, : w - 1] ** 2], np.ones(w), "valid")
        window = (int(np.argmax(energy)) + np.arange(w)) % n
        a, b = chips[i, window], x[window] - x[window].mean()
        best = max(best, (abs(a @ b) / (np.linalg.norm(a) * np.linalg.norm(b) + 1e-30), i))
    r, i = best
    return f"{r:.2f} (tooth {tooth[i]}, step {step[i]})"


def form(spec, conditions, base_label: str) -> None:
    """The real chip against the simulated ones (reads test records and labels: a diagnosis)."""
    labels = {f.path: f.label for f in spec["target"].files}
    positive = spec["target"].positive
    print(f"\nenergy % per order band ({', '.join(f'{a}-{b}' for a, b in BANDS)}) and the best local correlation")
    print(
        "| condition | signature | RMS | energy % | best simulated chip, local corr "
        "(as simulated / zero-phase gain / minimum-phase gain) |"
    )
    print("|---|---|---|---|---|")
    for c, cond in conditions.items():
        shown = detection.learned_input(spec, cond["max_order"])
        _, clean = twin(spec, cond)
        gain = history_gain(clean, cond)
        largest = np.flatnonzero(clean.intensity == clean.intensity.max())
        paths = {"as simulated": None, "zero-phase gain": gain, "minimum-phase gain": minimum_phase(gain)}
        chips = {name: shown(through(g, chip_responses(clean))) for name, g in paths.items()}
        for name, x in chips.items():
            print(f"| {c} | simulated chip, largest step, {name} | | {shares(x[largest])} | |")
        mean = {f.path: shown(r.mean(axis=0, keepdims=True))[0] for f, r in cond["history"] + cond["test"]}
        takes: dict[str, dict[str, str]] = {}
        for path in mean:
            take = re.search(r"_(\d+)\.zip$", path)
            if take:
                takes.setdefault(take.group(1), {})[labels[path]] = path
        for take, by_label in sorted(takes.items()):
            if base_label not in by_label:
                continue
            for label, path in sorted(by_label.items()):
                if label == base_label:
                    continue
                x = mean[path] - mean[by_label[base_label]]
                what = "chip" if label == positive else "control"
                rms = np.sqrt(np.mean(x**2))
                best = " / ".join(best_local(y, clean.tooth, clean.intensity, x) for y in chips.values())
                print(f"| {c} | take {take}: {label} less {base_label} ({what}) | {rms:.2f} | {shares(x)} | {best} |")


def deflection(sim: Simulator, faults, speed: float, load: float, revolutions: int = 4) -> np.ndarray:
    """Stage-1 mesh deflection P u (m) at every step of the last revolution, from the static equilibrium."""
    per_rev = sim.fs / speed
    steps = int(round(revolutions * per_rev))
    t = np.arange(steps + 1) / sim.fs
    tvms, _, k = sim._nominal_stiffness(faults, np.mod(2 * np.pi * speed * t, 2 * np.pi), per_rev, steps)
    F, (u, v, a) = sim._equilibrium(load, tvms.mean)
    shaft = 2 * np.pi * speed * t
    k_all = np.column_stack([k] + [sim._mesh_series(i, shaft, per_rev) for i in range(len(sim.meshes))])
    n, mu, GF = len(sim.dofs), np.array([sim.mu, *sim.mesh_mu]), sim.G @ F
    out, channel, d = np.empty((2, 1)), np.zeros(1, dtype=np.int64), np.empty(steps)
    for i in range(steps):  # one step per call: the state (u, v, a) is updated in place
        rows = np.ascontiguousarray(k_all[i + 1 : i + 2])
        _integrate_meshes(
            sim.GMC, GF, np.zeros((n, 0)), np.zeros((1, 0)), sim.Wm, sim.Pm, sim.PW, rows, mu,
            sim.c, 1.0 / sim.fs, sim.gamma, u, v, a, channel, out,
        )  # fmt: skip
        d[i] = sim.P @ u
    return d[-int(round(per_rev)) :]


def contact(spec) -> None:
    """Does the stage-1 mesh ever lose contact in the simulator (deflection <= 0)?"""
    source = spec["source"]
    registry = get_registry()
    model = registry.get("model", source.model)
    pair, _ = model.resolve(source.preset, None, source.name)
    fs = whole_steps_rate(source.fs, source.speed_hz, pair.Z1)  # as the dataset builder runs it
    sim = Simulator(model, source.preset, fs)
    kind, steps = source.faults[0]
    print(f"\nstage-1 mesh deflection over a revolution, um ({source.name}, {source.speed_hz:g} Hz, fs {fs:g} Hz)")
    print("| fault | load N m | min | mean | max | min / mean |")
    print("|---|---|---|---|---|---|")
    for step in (None, max(steps)):
        faults = [] if step is None else [place_fault(registry, sim.pair, kind, 1, step=step)]
        for load in (source.load_nm, source.load_nm / 5):
            d = deflection(sim, faults, source.speed_hz, load) * 1e6
            name = "healthy" if step is None else f"{kind}@1 step {step}"
            print(f"| {name} | {load:g} | {d.min():.3f} | {d.mean():.3f} | {d.max():.3f} | {d.min() / d.mean():.3f} |")


def main() -> None:
    parser = learned_parser(__doc__.splitlines()[0])
    parser.add_argument("--factors", nargs="*", type=float, default=[])
    parser.add_argument("--path", nargs="?", const="zero", choices=["zero", "minimum"])
    parser.add_argument("--form", action="store_true")
    parser.add_argument("--contact", action="store_true")
    parser.add_argument("--base-label", default="eccentric idler")
    args = parser.parse_args()
    scenario = learned_scenario(args)
    spec = scenario.spec
    if spec.get("corrected") is None:
        raise SystemExit(f"{args.scenario}: no [corrected] source to change")
    conditions = detection.read_target(spec["target"], spec["blocks"], lambda e: None)
    gains = {}
    if args.path:
        for cond in conditions.values():
            source, clean = twin(spec, cond)
            gain = history_gain(clean, cond)
            gains[source.name] = gain if args.path == "zero" else minimum_phase(gain)
    if args.contact:
        contact(spec)
    if args.form:
        form(spec, conditions, args.base_label)
    for factor in args.factors:
        print_factor(run_factor(scenario, args.out / f"x{factor:g}", factor, gains), factor)


if __name__ == "__main__":
    main()
