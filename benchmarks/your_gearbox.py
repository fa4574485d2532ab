"""Your own gearbox, as a user brings it: does `gearlab inspect` read random gearboxes' recordings right?

Each trial draws a spur gearbox whose tooth-count pairs no test, preset, example or scenario of
the project uses (one stage: z1 in 17..40, z2 = z1 x 1.2..4; two stages: each such a pair, the
second stage's module 1-1.5x the first's), writes its description as a user would (tooth counts,
module, face width, bores; no [dynamics]), and simulates one healthy record of it with gearlab's
simulator of that description (gearlab.data.simulated.simulated_record(gearbox=...): the model
integrated at >= 150 kHz, read at the logger's rate): input speed 15-50 Hz, load 5-40 N m, sensor
noise 10-30 dB under the record's RMS, a pinion run-out (shaft_eccentricity, 0-30 um) in half the
records, 4-8 s at a logger rate of 10-51.2 kHz (at least 5 samples per mesh period). Or, as an
evaluator's own generator would make it (--source synthetic; mix: either, drawn per trial): every
mesh's harmonics 1 to 3-8 amplitude-modulated by both of its shafts, a later mesh 0.3-1.5 times the
first, shaft lines, white noise, a speed swinging by up to 0.3 %.

The record is written in a random format, as loggers write them: CSV with a header (time column
`time_s`, `t`, `Time [s]`, `t (ms)` or `time`; comma, semicolon, tab or blank) or without one (a
`# fs = ...` line, or no rate: `--fs`), WAV int16 (`--gain`: the volts at full scale), HDF5
(an `fs` attribute), MATLAB v5, NPZ; in volts (`--sensitivity` in mV/g) or in m/s²; with a
once-per-revolution tacho, or without one. Without one the description says the speed as a user
knows it (within 0.5 % of the true speed: `declared`) or not at all (`found`: from the mesh lines).

`gearlab inspect FILE --gearbox DESC ... --json` (the CLI, in process) is then run with the right
description and with a wrong one (one gear's tooth count off by 1-3), measuring: each stage's mesh
order error (measured - the true mesh order; goal |e| <= 0.05), the speed error (goal |e| <= 0.5 %),
that the right description is said to match, and that the wrong one is called out (goal 100 %).
A wrong wheel count on the last stage shows only in that wheel's shaft sidebands: a healthy
simulated gear modulates nothing, so inspect says "not checked" there, reported apart ("last
wheel") for the simulator's records.

Selection rule (docs/learning.md): development seeds < 1000, reported figures on seeds >= 1000.

    python benchmarks/your_gearbox.py --trials 24 --seed 1000 [--stages 1 2] [--workers 1]
    python benchmarks/your_gearbox.py --seed 0 --stages 2 --only 5 --keep /tmp/look --verbose   # one again
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import re
import tempfile
from collections import defaultdict
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
G = 9.80665
SIM_FS = 150e3  # the model's integration rate, at least (the loggers' rates are too low for its modes)
MESH_GOAL, SPEED_GOAL = 0.05, 0.005
TIME_NAMES = (("time_s", 1.0), ("t", 1.0), ("Time [s]", 1.0), ("t (ms)", 1e3), ("time", 1.0))
DELIMITERS = (",", ";", "\t", " ")
RATES = (10e3, 12.8e3, 20e3, 25.6e3, 48e3, 51.2e3)
FORMATS = ("csv", "csv-bare", "wav", "h5", "mat", "npz")


def used_pairs() -> set[tuple[int, int]]:
    """Tooth-count pairs the project's tests, presets, examples, scenarios and docs use: 'a/b',
    'z1 = a ... z2 = b', '{z = a ...} ... {z = b ...}', '(a, b)' beside a 'z'."""
    pairs: set[tuple[int, int]] = set()
    patterns = (
        r"\b(\d{2,3})\s*/\s*(\d{2,3})\b",
        r"[zZ]1?\s*=\s*(\d{2,3})\D{1,60}?[zZ]2?\s*=\s*(\d{2,3})",
        r"\(\s*(\d{2,3})\s*,\s*(\d{2,3})\s*\)",
    )
    for folder in ("tests", "gearlab", "examples", "scenarios", "docs", "plugins"):
        for path in (ROOT / folder).rglob("*"):
            if path.suffix not in (".py", ".toml", ".md") or not path.is_file():
                continue
            text = path.read_text(errors="ignore")
            for pattern in patterns:
                pairs.update((int(a), int(b)) for a, b in re.findall(pattern, text))
    return pairs


def draw_stage(rng, used: set, module: float) -> dict:
    while True:
        z1 = int(rng.integers(17, 41))
        z2 = int(round(z1 * rng.uniform(1.2, 4.0)))
        if (z1, z2) not in used and z2 != z1:
            break
    root1 = module * (z1 - 2.5)
    return {
        "module": f"{module:g} mm",
        "face_width": f"{round(module * rng.uniform(8, 12)):g} mm",
        "pinion": {"z": z1, "bore": f"{max(8, round(0.45 * root1)):g} mm"},
        "wheel": {"z": z2, "bore": f"{max(10, round(0.3 * module * (z2 - 2.5))):g} mm"},
    }


def draw_gearbox(rng, stages: int, used: set) -> dict:
    m = float(rng.choice([1.5, 2.0, 2.5, 3.0]))
    out = [draw_stage(rng, used, m)]
    if stages == 2:
        out.append(draw_stage(rng, used, round(m * rng.uniform(1.0, 1.5) * 2) / 2))
    return {"stages": out}


def toml_text(name: str, box: dict, speed_hz: float | None, load_nm: float) -> str:
    lines = ["[gearbox]", f'name = "{name}"', "", "[operation]"]
    if speed_hz is not None:
        lines.append(f'speed = "{speed_hz:.4g} Hz"')
    lines.append(f'load = "{load_nm:.3g} N*m"')
    for s in box["stages"]:
        lines += ["", "[[stages]]", f'module = "{s["module"]}"', f'face_width = "{s["face_width"]}"']
        for gear in ("pinion", "wheel"):
            g = s[gear]
            lines.append(f'{gear} = {{ z = {g["z"]}, bore = "{g["bore"]}" }}')
    lines += ["", "[sensor]", 'near = "input"', 'direction = "x"', 'tacho = "input"', ""]
    return "\n".join(lines)


def wrong_counts(rng, box: dict) -> tuple[dict, str]:
    """The description with one gear's tooth count off by 1-3 (the pinion kept >= 17: no undercut)."""
    k = int(rng.integers(len(box["stages"])))
    gear = str(rng.choice(["pinion", "wheel"]))
    z = box["stages"][k][gear]["z"]
    delta = int(rng.choice([-3, -2, -1, 1, 2, 3]))
    if gear == "pinion" and z + delta < 17:
        delta = -delta
    wrong = json.loads(json.dumps(box))
    wrong["stages"][k][gear]["z"] = z + delta
    return wrong, f"s{k + 1}-{gear}{delta:+d}"


def write_recording(rec, rng, folder: Path, fmt: str, tacho: bool) -> tuple[Path, list[str], str]:
    """The record in *fmt* as a logger writes it: (path, the inspect options a user gives, units)."""
    volts = bool(rng.random() < 0.5)
    sens = float(rng.choice([10.0, 50.0, 100.0, 500.0]))  # mV/g
    scale = sens * 1e-3 / G if volts else 1.0
    acc = rec.vibration * scale
    opts = ["--sensitivity", f"{sens:g} mV/g"] if volts else []
    units = f"{sens:g} mV/g" if volts else "m/s2"
    stem = folder / "rec"
    if fmt in ("csv", "csv-bare"):
        path = stem.with_suffix(".csv")
        if fmt == "csv":
            delim = DELIMITERS[int(rng.integers(len(DELIMITERS)))]
            # a blank-separated file cannot hold a name with a blank ('Time [s]'): its logger writes none
            names = [t for t in TIME_NAMES if delim != " " or " " not in t[0]]
            tname, tscale = names[int(rng.integers(len(names)))]
            vname = ("acc_V" if volts else "acc_ms2") if rng.random() < 0.5 else "ch1"
            names = [tname, vname] + (["tacho_V"] if tacho else [])
            cols = [rec.t * tscale, acc] + ([rec.tacho] if tacho else [])
            head, comment = delim.join(names), ""
            opts += ["--vibration", vname] + (["--tacho", "tacho_V"] if tacho else [])
        else:  # no header: columns 0, 1, ...; the rate in a comment line or given on the command line
            delim = DELIMITERS[int(rng.integers(len(DELIMITERS)))]
            cols = [acc] + ([rec.tacho] if tacho else [])
            head = None
            if rng.random() < 0.5:
                comment = f"# fs = {rec.fs:.10g}"
            else:
                comment = ""
                opts += ["--fs", f"{rec.fs:.10g} Hz"]
            opts += ["--vibration", "0"] + (["--tacho", "1"] if tacho else [])
        table = np.column_stack(cols)
        body = "\n".join(delim.join(f"{v:.7g}" for v in row) for row in table)
        text = "\n".join(x for x in (comment, head) if x) + ("\n" if (comment or head) else "") + body + "\n"
        path.write_text(text)
    elif fmt == "wav":
        from scipy.io import wavfile

        path = stem.with_suffix(".wav")
        full = float(np.max(np.abs(acc))) * 2.0  # the full scale the logger's range gives, ~2x the peak
        chans = [acc / full] + ([rec.tacho / 10.0] if tacho else [])
        data = np.round(np.column_stack(chans) * 32767).astype(np.int16)
        wavfile.write(path, int(round(rec.fs)), data)
        # the vibration's units per full scale: volts (then the sensitivity), or m/s² itself
        opts += ["--gain", f"{full * (1e3 if volts else 1.0):.6g} {'mV' if volts else 'V'}", "--vibration", "0"]
        opts += ["--tacho", "1"] if tacho else []
    elif fmt == "h5":
        import h5py

        path = stem.with_suffix(".h5")
        with h5py.File(path, "w") as f:
            g = f.create_group("run1")
            g.attrs["fs"] = rec.fs
            g["acc"] = acc
            if tacho:
                g["tacho"] = rec.tacho
        opts += ["--vibration", "run1/acc"] + (["--tacho", "run1/tacho"] if tacho else [])
    elif fmt == "mat":
        from scipy.io import savemat

        path = stem.with_suffix(".mat")
        data = {"acc": acc[:, None], "Fs": np.array([[rec.fs]])}
        if tacho:
            data["tacho"] = rec.tacho[:, None]
        savemat(path, data)
        opts += ["--vibration", "acc"] + (["--tacho", "tacho"] if tacho else [])
    else:
        path = stem.with_suffix(".npz")
        data = {"acc": acc, "fs": np.array(rec.fs)}
        if tacho:
            data["tacho"] = rec.tacho
        np.savez(path, **data)
        opts += ["--vibration", "acc"] + (["--tacho", "tacho"] if tacho else [])
    return path, opts, units


@dataclass(frozen=True)
class Synthetic:
    """A record made outside gearlab's simulator, as an evaluator's own generator would make it."""

    vibration: np.ndarray
    tacho: np.ndarray
    fs: float
    speed_hz: float  # the input shaft's mean speed over the record

    @property
    def t(self) -> np.ndarray:
        return np.arange(self.vibration.size) / self.fs


def synthetic_record(box: dict, speed: float, fs: float, seconds: float, snr_db: float, rng) -> Synthetic:
    """Every mesh's harmonics 1-3..8 (random, falling amplitudes; a later stage 0.3-1.5 times the
    first's), amplitude-modulated by both of its shafts (depths 5-30 %), shaft lines, white noise at
    *snr_db*; the input shaft's speed swinging by up to 0.3 % (a motor's), a 0-5 V pulse tacho."""
    n = int(seconds * fs)
    t = np.arange(n) / fs
    swing, rate = rng.uniform(0.0, 0.003), rng.uniform(0.2, 1.0)
    theta = 2 * np.pi * speed * t + swing * speed / rate * (1 - np.cos(2 * np.pi * rate * t))
    x, o, orders = np.zeros(n), 1.0, [1.0]
    for k, stage in enumerate(box["stages"]):
        z1, z2 = stage["pinion"]["z"], stage["wheel"]["z"]
        level = 1.0 if k == 0 else rng.uniform(0.3, 1.5)
        mod = (
            1
            + rng.uniform(0.05, 0.3) * np.cos(o * theta + rng.uniform(0, 6))
            + rng.uniform(0.05, 0.3) * np.cos(o * z1 / z2 * theta + rng.uniform(0, 6))
        )
        for h in range(1, int(rng.integers(3, 9)) + 1):
            x += level * rng.uniform(0.2, 1.0) / h * mod * np.cos(h * o * z1 * theta + rng.uniform(0, 6))
        o *= z1 / z2
        orders.append(o)
    for q in orders:
        x += 0.1 * np.cos(q * theta + rng.uniform(0, 6))
    x = (x + rng.standard_normal(n) * np.std(x) * 10 ** (-snr_db / 20)) * rng.uniform(0.5, 5.0)
    tacho = np.where(np.mod(theta, 2 * np.pi) < 0.3, 5.0, 0.0)
    return Synthetic(x, tacho, fs, float((theta[-1] - theta[0]) / (2 * np.pi * (n - 1) / fs)))


def inspect_cli(args: list[str]) -> dict:
    """`gearlab inspect ... --json` in process: its JSON, or {"error": the one line}."""
    from gearlab.cli import app
    from gearlab.errors import GearlabInputError

    out = io.StringIO()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
            app(["inspect", *args, "--json"], standalone_mode=False)
    except GearlabInputError as exc:
        return {"error": str(exc)}
    except Exception as exc:  # a crash is a finding, not the end of the benchmark
        return {"error": f"CRASH {type(exc).__name__}: {exc}"}
    return json.loads(out.getvalue())


def trial(args: tuple) -> dict:
    import warnings

    from gearlab.data.simulated import simulated_record

    seed, index, stages, keep, source = args
    rng = np.random.default_rng([seed, index, stages])
    box = draw_gearbox(rng, stages, USED)
    speed = float(rng.uniform(15.0, 50.0))
    load = float(rng.uniform(5.0, 40.0))
    snr = float(rng.uniform(10.0, 30.0))
    z1 = box["stages"][0]["pinion"]["z"]
    fs = float(next((r for r in rng.permutation(RATES) if r >= 5 * z1 * speed), max(RATES)))
    seconds = float(rng.uniform(4.0, 8.0))
    runout = float(rng.uniform(5e-6, 30e-6)) if rng.random() < 0.5 else 0.0
    fmt = str(rng.choice(FORMATS))
    tacho = bool(rng.random() < 0.5)
    mode = "tacho" if tacho else str(rng.choice(["declared", "found"]))
    declared = speed * (1 + rng.uniform(-0.005, 0.005)) if mode == "declared" else None
    effects = [{"name": "shaft_eccentricity", "e": runout, "phase": float(rng.uniform(0, 2 * np.pi))}] if runout else []
    # the record's maker: gearlab's simulator of the description, or another generator (its own stream,
    # so a trial's gearbox, speed, format ... are the same whichever made its record)
    maker = (
        source
        if source != "mix"
        else ("sim", "synthetic")[int(np.random.default_rng([seed, index, stages, 7]).integers(2))]
    )
    row = {
        "seed": seed,
        "index": index,
        "stages": stages,
        "counts": "+".join(f"{s['pinion']['z']}/{s['wheel']['z']}" for s in box["stages"]),
        "speed_hz": speed,
        "fs": fs,
        "format": fmt,
        "mode": mode,
        "snr_db": snr,
        "runout_um": runout * 1e6,
        "source": maker,
    }
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        if keep:  # the trial's files kept for a look with the CLI (--keep DIR)
            folder = Path(keep) / f"s{seed}-{stages}-{index}"
            folder.mkdir(parents=True, exist_ok=True)
        right = folder / "right.toml"
        right.write_text(toml_text("right", box, declared, load))
        sim_seed = int(rng.integers(1 << 30))
        if maker == "synthetic":
            rec = synthetic_record(box, speed, fs, seconds, snr, np.random.default_rng([seed, index, stages, 8]))
            speed = row["speed_hz"] = rec.speed_hz
        else:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                rec = simulated_record(
                    gearbox=str(right),
                    speed_hz=speed,
                    load_nm=load,
                    revolutions=seconds * speed,
                    snr_db=snr,
                    effects=effects,
                    seed=sim_seed,
                    fs=fs,
                    sim_fs=SIM_FS,
                )
        path, opts, units = write_recording(rec, rng, folder, fmt, tacho)
        row["units"] = units
        if keep:
            quoted = " ".join(f"'{x}'" if " " in x else x for x in opts)
            (folder / "inspect.sh").write_text(
                f"# {json.dumps(row)}\ngearlab inspect {path.name} --gearbox right.toml {quoted}\n"
                f"gearlab inspect {path.name} --gearbox wrong.toml {quoted}\n"
            )
        got = inspect_cli([str(path), "--gearbox", str(right), *opts])
        row["error"] = got.get("error")
        if "error" not in got:
            row["speed_err"] = got["speed"]["mean_hz"] / speed - 1
            true_mesh = []
            o = 1.0
            for s in box["stages"]:
                true_mesh.append(o * s["pinion"]["z"])
                o *= s["pinion"]["z"] / s["wheel"]["z"]
            row["mesh_err"] = [
                (st.get("measured_order", math.nan) - m) for st, m in zip(got["check"]["stages"], true_mesh)
            ]
            row["matches"] = got["matches"]  # True, False, or None: the pinion cannot be confirmed (no speed)
            row["verdict"] = got["verdict"]
        wrong, what = wrong_counts(rng, box)
        bad = folder / "wrong.toml"
        bad.write_text(toml_text("wrong", wrong, declared, load))
        row["wrong"] = what
        got = inspect_cli([str(path), "--gearbox", str(bad), *opts])
        if "error" in got:
            # a refusal that names the mismatch (an ambiguous speed, no line fits) is a call-out too
            row["wrong_called"], row["wrong_verdict"] = not got["error"].startswith("CRASH"), got["error"]
            row["wrong_unconfirmed"] = False
        else:
            # None (cannot be confirmed without a speed) is no call-out: kept apart in the table
            row["wrong_called"], row["wrong_verdict"] = got["matches"] is False, got["verdict"]
            row["wrong_unconfirmed"] = got["matches"] is None
        last = len(box["stages"])
        # a last stage's wheel shows only in its shaft's sidebands, which a healthy simulated gear lacks
        row["wrong_unseen"] = maker == "sim" and what.startswith(f"s{last}-wheel")
    return row


USED: set = set()


def _init(used):
    USED.update(used)


def quantiles(values) -> str:
    v = np.abs(np.asarray([x for x in values if np.isfinite(x)]))
    if v.size == 0:
        return "-"
    q50, q90, qmax = np.quantile(v, [0.5, 0.9, 1.0])
    return f"{q50:.3g} / {q90:.3g} / {qmax:.3g}"


def table(rows: list[dict]) -> str:
    groups = defaultdict(list)
    for r in rows:
        groups[(r["source"], r["stages"], "tacho" if r["mode"] == "tacho" else "no tacho: " + r["mode"])].append(r)
    out = [
        "| maker | stages | speed from | records | errors | mesh-order error 50/90/max (orders) | within 0.05 "
        "| speed error % 50/90/max | within 0.5 % | right: matched / cannot confirm / differs "
        "| wrong called out (seen; cannot confirm) | wrong called out (last wheel) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for (maker, stages, mode), rs in sorted(groups.items()):
        ok = [r for r in rs if not r["error"]]
        mesh = [e for r in ok for e in r["mesh_err"]]
        speed = [100 * r["speed_err"] for r in ok]
        seen = [r for r in rs if not r["wrong_unseen"]]
        unseen = [r for r in rs if r["wrong_unseen"]]
        out.append(
            f"| {maker} | {stages} | {mode} | {len(rs)} | {len(rs) - len(ok)} | {quantiles(mesh)} | "
            f"{sum(abs(e) <= MESH_GOAL for e in mesh)}/{len(mesh)} | {quantiles(speed)} | "
            f"{sum(abs(e) <= 100 * SPEED_GOAL for e in speed)}/{len(speed)} | "
            f"{sum(r['matches'] is True for r in ok)} / {sum(r['matches'] is None for r in ok)} / "
            f"{sum(r['matches'] is False for r in ok)} of {len(ok)} | "
            f"{sum(r['wrong_called'] for r in seen)}/{len(seen)}; {sum(r['wrong_unconfirmed'] for r in seen)} | "
            f"{sum(r['wrong_called'] for r in unseen)}/{len(unseen)} |"
        )
    return "\n".join(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=12, help="trials per number of stages")
    parser.add_argument("--seed", type=int, default=0, help="< 1000 development, >= 1000 reported")
    parser.add_argument("--stages", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--rows", type=Path, help="write every trial's row here (JSON lines)")
    parser.add_argument("--verbose", action="store_true", help="print each trial's row as it finishes")
    parser.add_argument(
        "--source", choices=("mix", "sim", "synthetic"), default="mix", help="the records' maker (mix: either, drawn)"
    )
    parser.add_argument("--only", type=int, nargs="+", help="these trial indices only (to look at one again)")
    parser.add_argument("--keep", type=Path, help="keep each trial's description and recording under this folder")
    a = parser.parse_args()
    used = used_pairs()
    keep = str(a.keep.resolve()) if a.keep else ""
    jobs = [(a.seed, i, s, keep, a.source) for s in a.stages for i in range(a.trials) if not a.only or i in a.only]
    rows = []
    if a.workers > 1:
        with ProcessPoolExecutor(a.workers, initializer=_init, initargs=(used,)) as pool:
            for row in pool.map(trial, jobs):
                rows.append(row)
                if a.verbose:
                    print(json.dumps(row), flush=True)
    else:
        _init(used)
        for job in jobs:
            rows.append(trial(job))
            if a.verbose:
                print(json.dumps(rows[-1]), flush=True)
    if a.rows:
        a.rows.write_text("".join(json.dumps(r) + "\n" for r in rows))
    print(table(rows))
    for r in rows:
        problems = []
        if r["error"]:
            problems.append(f"error: {r['error']}")
        else:
            if any(not abs(e) <= MESH_GOAL for e in r["mesh_err"]) or abs(r["speed_err"]) > SPEED_GOAL:
                problems.append(f"mesh err {r['mesh_err']}, speed err {100 * r['speed_err']:.3f} %")
            if r["matches"] is not True:
                problems.append(f"right said: {r['verdict']}")
        if not r["wrong_called"] and not r["wrong_unseen"]:
            problems.append(f"wrong {r['wrong']} said: {r['wrong_verdict']}")
        if problems:
            print(
                f"- seed {r['seed']} #{r['index']} {r['source']} {r['counts']} {r['speed_hz']:.2f} Hz {r['format']} "
                f"{r['mode']} {r['units']} fs {r['fs']:g}: " + " | ".join(problems)
            )


if __name__ == "__main__":
    main()
