"""Small synthetic records in the PHM 2009 text format (tests, and benchmarks/phm09_other_damage.py): a zip of one
whitespace-separated text with columns accelerometer (V), second accelerometer (V), tacho (V)."""

import zipfile
from pathlib import Path

import numpy as np

FS = 8192.0  # Hz
SPEED = 16.0  # Hz: 512 samples per revolution
PULSES = 10  # tacho marks per revolution
TEETH = 32
SENSITIVITY = 0.01 / 9.80665  # 10 mV/g in V per m/s²


def signals(
    revolutions: int = 40,
    chip: float = 0.0,
    seed: int = 0,
    phase: float = 0.0,
    speed: float = SPEED,
    noise: float = 0.3,
) -> tuple[np.ndarray, np.ndarray]:
    """(vibration in m/s², tacho in V): a mesh tone at order TEETH, noise, and with *chip* > 0
    a short impulse once per revolution (the chipped tooth); *phase*: the shaft angle (rad)
    at the first sample, so a record may start anywhere."""
    rng = np.random.default_rng(seed)
    n = int(revolutions * FS / speed)
    theta = phase + 2 * np.pi * speed * np.arange(n) / FS
    vib = np.sin(TEETH * theta) + 0.3 * np.sin(2 * TEETH * theta + 0.4) + 0.2 * np.sin(theta)
    if chip:
        # a decaying ring each time the chipped tooth (at 1 rad) meshes
        since = np.mod(theta - 1.0, 2 * np.pi) / (2 * np.pi * speed)  # seconds since the tooth met
        vib += chip * np.exp(-since * 2000.0) * np.sin(2 * np.pi * 1500.0 * since)
    vib += noise * rng.standard_normal(n)
    tacho = np.where(np.mod(theta * PULSES / (2 * np.pi), 1.0) < 0.3, 5.0, 0.05)
    return vib, tacho


def text(vib: np.ndarray, tacho: np.ndarray, header: str | None = None) -> bytes:
    volts = vib * SENSITIVITY
    table = np.column_stack([volts, 0.5 * volts, tacho])
    # np.savetxt's bytes, formatted in one operation: savetxt formats row by row, 2.3 times slower
    # (0.44 s for a rig record of 46 revolutions), and the tests write dozens of records
    body = ("%.7e  %.7e  %.7e\n" * len(table)) % tuple(table.ravel().tolist())
    return ((header + "\n") if header else "").encode() + body.encode()


def write_zip(path: Path, data: bytes, member: str = "record.txt") -> Path:
    # the fastest deflate level: the same member, 4 times faster to write than the default level
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=1) as z:
        z.writestr(member, data)
    return path


def record(path: Path, **kw) -> Path:
    return write_zip(Path(path), text(*signals(**kw)))


def scaled_record(path: Path, seed: int, scale: float, revolutions: int = 40) -> Path:
    """A record of *revolutions* turns whose vibration is *scale* times the plain one's (another load's level)."""
    vib, tacho = signals(revolutions=revolutions, seed=seed, phase=0.7 * seed)
    return write_zip(Path(path), text(scale * vib, tacho))


def rig_record(
    path: Path, speed=35.0, seed=3, chip=0.0, idler=0.0, output=0.0, bearing=0.0, phase=2.7, eccentric=0.0
) -> Path:
    """A synthetic record of the PHM rig's layout at its rate (FS must be set to it):
    the mesh tone and noise of signals (46 revolutions), a chipped input pinion tooth
    (*chip*: a ring once a revolution), a chipped tooth on the idler shaft (*idler*: once every 3
    input revolutions, at the same input angle), on the output shaft (*output*: every 5th) or an
    outer-race bearing defect (*bearing*: a ring 3.05 times per input revolution). *eccentric*: an
    eccentric idler, which multiplies the mesh and the pinion chip's ring by 1 + eccentric·cos(θ/3 − 0.5)
    (θ the input angle: once per idler turn, smooth, never reversing for eccentric <= 1)."""
    vib, tacho = signals(revolutions=46, chip=0.0 if eccentric else chip, seed=seed, phase=phase, speed=speed)
    t = np.arange(len(vib)) / FS
    theta = phase + 2 * np.pi * speed * t
    if eccentric:  # signals' mesh and chip, modulated by the idler's turn
        swing = eccentric * np.cos(theta / 3 - 0.5)
        vib = vib + swing * (np.sin(TEETH * theta) + 0.3 * np.sin(2 * TEETH * theta + 0.4))
        since = np.mod(theta - 1.0, 2 * np.pi) / (2 * np.pi * speed)
        vib = vib + chip * (1 + swing) * np.exp(-since * 2000.0) * np.sin(2 * np.pi * 1500.0 * since)
    for size, q, at in ((idler, 3, 2.0), (output, 5, 4.0)):  # the slow shaft's tooth meets at *at* rad
        if size:
            since = np.mod(theta / q - at, 2 * np.pi) / (2 * np.pi * speed / q)
            vib = vib + size * np.exp(-since * 2000.0) * np.sin(2 * np.pi * 1500.0 * since)
    if bearing:
        since = np.mod(t * speed * 3.05, 1.0) / (speed * 3.05)
        vib = vib + bearing * np.exp(-since * 2000.0) * np.sin(2 * np.pi * 1500.0 * since)
    return write_zip(path, text(vib, tacho))
