"""docs/your_gearbox.md step 5 on a take too short for record30 (issue 39, helper BF's 37/83 box without a
tacho): the guide said `gearlab validate` refuses one at its declared speed and warns of one 'read by its
tacho' at the description's speed; a WAV take with neither a tacho nor a declared speed (its speed found
from the mesh lines in the run) is warned of too, and the guide now says so. The takes are made here with
numpy: a single 37/83 mesh at 22 Hz, 2 s (19 output-shaft turns) against 3 s history takes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.io.wavfile
from gearboxes import description, stage

FS = 8192
SPEED = 22.0  # Hz: the output gear 83T turns 22 x 37 / 83 = 9.8 times a second, 30 turns in 3.06 s


def _take(path: Path, seconds: float) -> str:
    t = np.arange(int(FS * seconds)) / FS
    th = 2 * np.pi * SPEED * t
    x = (1 + 0.2 * np.cos(th * 37 / 83)) * np.cos(37 * th) + np.random.default_rng(2).normal(0, 0.05, t.size)
    scipy.io.wavfile.write(path, FS, x.astype(np.float32))
    return path.name


@pytest.mark.parametrize("declared", [False, True])
def test_a_short_take_without_a_tacho_is_warned_of_its_speed_found_refused_declared(cli, tmp_path, declared):
    box = description(stage(37, 83, module="2.5 mm"), name="boxC", speed="22 Hz", load="40 N*m")
    (tmp_path / "box.toml").write_text(box)
    history = [_take(tmp_path / f"h{i}.wav", 3.5) for i in (1, 2)]
    short = _take(tmp_path / "short.wav", 2.0)
    speed = ', speed = "22 Hz"' if declared else ""
    files = [f'{{ file = "{h}", role = "history", label = "healthy" }}' for h in history]
    files.append(f'{{ file = "{short}", role = "test", label = "fault"{speed} }}')
    (tmp_path / "d.toml").write_text(
        '[scenario]\nname = "c"\nkind = "detection"\n[source]\ngearbox = "box.toml"\n'
        'faults = { "chip@output gear" = [18] }\nhealthy = 8\n'
        '[target]\nunit = "g"\nfiles = [\n' + ",\n".join(files) + ",\n]\n"
        '[[methods]]\nadapter = "matched_filter"\n'
    )
    code, out, err = cli("validate", tmp_path / "d.toml")
    said = "short.wav: 2 s at 22 Hz holds ~19 turns of the output shaft; record30 needs 30 (a take of >= 3.1 s)"
    assert said in err, out + err
    if declared:
        assert code == 2 and len(err.strip().splitlines()) == 1, out + err
    else:
        assert code == 0 and out.startswith("OK"), out + err
        assert "unless it runs faster than the description's speed" in err, err
    guide = " ".join((Path(__file__).parents[1] / "docs" / "your_gearbox.md").read_text().split())
    assert "refuses a shorter one whose header gives its length and rate" in guide
    warned = "warns of one whose speed the run reads (by its tacho, or from the mesh lines where no `speed` is given)"
    assert warned in guide
