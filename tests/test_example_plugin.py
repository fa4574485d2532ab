"""The out-of-tree example plugin (examples/gearlab-wear) and broken third-party plugins,
seen the way a user sees them: installed as a distribution, found through its entry point,
used from the `gearlab` command.

The example is installed once per module with pip into a temporary directory (offline,
no build isolation); the CLI runs as a subprocess with that directory on PYTHONPATH, so
importlib.metadata finds the distribution and its entry point exactly as after a real
`pip install`.
"""

import importlib.util
import itertools
import json
import math
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from gearlab.errors import GearlabInputError
from gearlab.physics.faults import place_fault
from gearlab.physics.sections import healthy_section
from gearlab.physics.stiffness import contact_geometry

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "gearlab-wear"
BUILTIN_FAULTS = {"crack", "chip", "broken_tip", "spall", "pit"}
MEAN = re.compile(r"TVMS mean (\S+) N/m")


def gearlab(*args, path: Path, cwd: Path) -> subprocess.CompletedProcess:
    """Run `python -m gearlab ARGS` with *path* in front of the import path."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(path), env.get("PYTHONPATH", "")]))
    env["GEARLAB_CACHE"] = str(cwd / "cache")
    command = [sys.executable, "-m", "gearlab", *map(str, args)]
    return subprocess.run(command, capture_output=True, text=True, cwd=cwd, env=env, timeout=300, check=False)


def printed_mean(result: subprocess.CompletedProcess) -> float:
    assert result.returncode == 0, result.stderr
    return float(MEAN.search(result.stdout).group(1))


# ----------------------------------------------------------------------------- the example, installed


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """examples/gearlab-wear installed with pip into a fresh directory (built from a copy,
    so the in-tree build leaves no build/ or egg-info behind in the repository)."""
    work = tmp_path_factory.mktemp("wear")
    source = shutil.copytree(EXAMPLE, work / "src", ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    target = work / "site"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "--no-deps",
            "--no-build-isolation",
            "--no-index",
            "--disable-pip-version-check",
            "--quiet",
            "--target",
            str(target),
            str(source),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    return target


@pytest.fixture(scope="module")
def wear(site):
    """The installed module's fault object, loaded from its file (no change to sys.path)."""
    spec = importlib.util.spec_from_file_location("gearlab_wear_under_test", site / "gearlab_wear" / "wear.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    (fault,) = module.gearlab_faults()
    return fault


def test_wear_listed_with_its_package_and_params(site, tmp_path):
    result = gearlab("plugins", "--json", path=site, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    rows = json.loads(result.stdout)
    assert not [r for r in rows if r["kind"] == "problem"]
    (row,) = [r for r in rows if r["kind"] == "fault" and r["name"] == "wear"]
    assert row["package"] == "gearlab-wear"
    assert row["doc"]
    params = {p["name"]: p for p in row["params"]}
    assert set(params) == {"depth", "band_start", "band_end"}
    assert params["depth"]["unit"] == "m" and params["depth"]["display_unit"] == "mm"
    assert params["depth"]["low"] == 0.0 < params["depth"]["high"]
    assert params["band_start"]["default"] < params["band_end"]["default"] <= params["band_end"]["high"] == 1.0
    # the built-ins are still there, and still belong to gearlab
    assert {r["name"] for r in rows if r["kind"] == "fault" and r["package"] == "gearlab"} == BUILTIN_FAULTS


def test_wear_lowers_the_mean_tvms_from_the_cli(site, tmp_path):
    healthy = printed_mean(gearlab("stiffness", "--preset", "luo2019", path=site, cwd=tmp_path))
    result = gearlab("stiffness", "--preset", "luo2019", "--fault", "wear@3=10", path=site, cwd=tmp_path)
    worn = printed_mean(result)
    assert worn < healthy
    assert re.search(r"wear@3: RFA 0\.0[1-9]", result.stdout), result.stdout  # step 10: a few per cent


def test_wear_in_a_stiffness_scenario(site, tmp_path):
    scenario = tmp_path / "wear.toml"
    scenario.write_text(
        """
[scenario]
name = "wear_ladder"
kind = "stiffness"
description = "the wear ladder of the example plugin"

[stiffness]
pair = "luo2019"
points = 1024

[sweep]
faults = ["wear"]
tooth = 3
steps = [1, 20]

[[cases]]
name = "worn_lower_flank"
faults = [{ kind = "wear", tooth = 3, params = { depth = "0.3 mm", band_start = 0.1, band_end = 0.5 } }]
"""
    )
    result = gearlab("run", scenario, "--out", tmp_path / "runs", "--quick", path=site, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    last = result.stdout.strip().splitlines()[-1]
    assert last.startswith("run directory: ")
    run_dir = Path(last.removeprefix("run directory: "))
    summary = json.loads((run_dir / "summary.json").read_text())
    steps = summary["sweep"]["wear"]
    means = [steps[s]["mean"] for s in sorted(steps, key=int)]
    assert len(means) == 3 and means[0] == summary["healthy"]["mean"] and means[0] > means[1] > means[2]
    assert summary["cases"]["worn_lower_flank"]["mean_N_per_m"] < summary["healthy"]["mean"]

    # a depth that wears through the tooth is refused before any work, naming the parameter
    scenario.write_text(scenario.read_text().replace('depth = "0.3 mm"', 'depth = "6 mm"'))
    result = gearlab("validate", scenario, path=site, cwd=tmp_path)
    assert result.returncode == 2 and "eats the tooth" in result.stderr, result.stderr


# ----------------------------------------------------------------------------- the wear physics


def test_zero_wear_is_healthy(wear, pairs, models):
    pair = pairs["luo2019"]
    healthy = healthy_section(pair.pinion, pair.face_width)
    params = wear.resolve({}, pair)
    assert params["depth"] == 0.0
    section = wear.apply(healthy, params, pair)
    for name in ("h", "A", "I", "L"):
        assert np.array_equal(getattr(section, name), getattr(healthy, name))
    step1 = place_fault_on(wear, pair, tooth=3, step=1)
    assert np.array_equal(
        models["luo2019"].mesh_stiffness([step1], 1024).k, models["luo2019"].mesh_stiffness((), 1024).k
    )
    assert wear.rfa(params, pair) == 0.0


def place_fault_on(fault, pair, tooth, step):
    return fault.place(tooth, fault.resolve(fault.at_step(pair, step), pair), pair)


@pytest.mark.parametrize("name", ["luo2019", "meng2020"])
def test_stiffness_falls_and_rfa_grows_monotonically_along_the_ladder(wear, pairs, models, name):
    pair, model = pairs[name], models[name]
    ladder = wear.ladder(pair)
    assert len(ladder) == 20 and ladder[0]["depth"] == 0.0
    depths = [p["depth"] for p in ladder]
    assert all(b > a for a, b in itertools.pairwise(depths))
    means, minima, rfas = [], [], []
    for step in range(1, 21):
        placed = place_fault_on(wear, pair, tooth=5, step=step)
        k = model.mesh_stiffness([placed], 1024).k
        means.append(k.mean())
        minima.append(k.min())
        rfas.append(wear.rfa(placed.params, pair))
    assert all(b < a for a, b in itertools.pairwise(means))
    assert all(b <= a for a, b in itertools.pairwise(minima)) and minima[-1] < minima[0]
    assert rfas[0] == 0.0 and all(b > a for a, b in itertools.pairwise(rfas))
    assert rfas[-1] < 0.25  # a surface fault: well below a crack's 1 (Figure 2.32)


def test_band_limits_where_the_section_and_the_stiffness_change(wear, pairs, models):
    pair, model = pairs["luo2019"], models["luo2019"]
    healthy = healthy_section(pair.pinion, pair.face_width)
    params = wear.resolve({"depth": "0.3 mm", "band_start": 0.55, "band_end": 0.8}, pair)
    worn = wear.apply(healthy, params, pair)
    x0, x1 = 0.55 * healthy.tooth_height, 0.8 * healthy.tooth_height
    on = (healthy.x >= x0) & (healthy.x <= x1)
    assert on.any() and not on.all()
    # one flank loses 0.3 mm: the half thickness 0.15 mm, on the band only
    assert np.allclose(healthy.h[on] - worn.h[on], 0.15e-3, rtol=0, atol=1e-15)
    assert np.array_equal(worn.h[~on], healthy.h[~on])
    for name in ("A", "I"):
        assert np.array_equal(getattr(worn, name)[~on], getattr(healthy, name)[~on])
    assert np.array_equal(worn.L, healthy.L)  # no change to the face width: Hertz untouched
    # A_x, I_x stay those of a strip of half thickness h_x (eq. 2.18, 2.19 form)
    assert np.allclose(worn.A, 2 * worn.h * worn.L, rtol=1e-12)
    assert np.allclose(worn.I, 2.0 / 3.0 * worn.h**3 * worn.L, rtol=1e-12)

    # A contact below the band loads a beam that is healthy up to it: same stiffness.
    # Above the band's start the contact sees the thinner strip: lower stiffness.
    phi = np.linspace(0.0, pair.theta_t, 400)
    d, _ = contact_geometry(pair.pinion, pair.alpha1_pinion(phi))
    placed = wear.place(4, params, pair)
    k_worn, k_healthy = model.tooth_pair_stiffness(phi, [placed]), model.tooth_pair_stiffness(phi)
    below, above = d < x0 - 1e-6, d > x0 + 0.05e-3
    assert below.any() and above.any()
    assert np.allclose(k_worn[below], k_healthy[below], rtol=1e-12)
    assert np.all(k_worn[above] < k_healthy[above])


def test_check_refuses_impossible_wear(wear, pairs):
    pair = pairs["meng2020"]
    healthy = healthy_section(pair.pinion, pair.face_width)
    tip_thickness = 2 * healthy.h[-1]  # the thinnest point of a band that reaches the tip
    with pytest.raises(GearlabInputError, match="eats the tooth"):
        wear.resolve({"depth": tip_thickness}, pair)
    wear.resolve({"depth": 0.99 * tip_thickness}, pair)  # just short of it is allowed
    # the same depth is allowed on a band lower down, where the tooth is thicker
    wear.resolve({"depth": tip_thickness, "band_start": 0.1, "band_end": 0.3}, pair)
    with pytest.raises(GearlabInputError, match="band_start"):
        wear.resolve({"band_start": 0.7, "band_end": 0.6}, pair)
    with pytest.raises(GearlabInputError, match="outside"):
        wear.resolve({"depth": "-0.1 mm"}, pair)
    # the worst ladder step is a legal wear state
    wear.resolve(wear.at_step(pair, 20), pair)


def test_example_uses_only_the_public_plugin_api():
    source = (EXAMPLE / "gearlab_wear" / "wear.py").read_text()
    imported = set(re.findall(r"^\s*(?:from|import) (gearlab[\w.]*)", source, re.MULTILINE))
    assert imported == {"gearlab.api"}, imported  # the declared plugin API, nothing private


# ----------------------------------------------------------------------------- broken third-party plugins


def fake_distribution(site: Path, dist: str, module: str, code: str) -> None:
    """What pip leaves behind for a one-module distribution with one `gearlab` entry point."""
    (site / f"{module}.py").write_text(code)
    info = site / f"{dist.replace('-', '_')}-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[gearlab]\n{module} = {module}\n")


FAULT_HEAD = """
from gearlab.api import MM, Fault, NoParams, hookimpl, parameters, setting
"""


@pytest.fixture(scope="module")
def broken_site(tmp_path_factory) -> Path:
    site = tmp_path_factory.mktemp("broken")
    fake_distribution(site, "gearlab-needs-missing", "needs_missing", "import a_library_nobody_installed  # noqa\n")
    fake_distribution(
        site,
        "gearlab-bad-schema",
        "bad_schema",
        FAULT_HEAD
        + """
class Bump(Fault):
    name = "bump"
    params = parameters(height=setting(float, 2e-3, low=0.0, high=1e-3, **MM, doc="above its bound"))

    def apply(self, section, params, pair):
        return section

    def ladder_endpoints(self, pair):
        return {"height": 0.0}, {"height": 1e-3}


@hookimpl
def gearlab_faults():
    return [Bump()]
""",
    )
    fake_distribution(
        site,
        "gearlab-crack-clash",
        "crack_clash",
        FAULT_HEAD
        + """
class Impostor(Fault):
    name = "crack"
    params = NoParams

    def apply(self, section, params, pair):
        raise RuntimeError("the impostor crack was used")

    def ladder_endpoints(self, pair):
        return {}, {}


@hookimpl
def gearlab_faults():
    return [Impostor()]
""",
    )
    return site


EXPECTED_PROBLEMS = {
    "gearlab-needs-missing": "a_library_nobody_installed",
    "gearlab-bad-schema": "outside its bounds",
    "gearlab-crack-clash": "already registered by package 'gearlab'",
}


def test_broken_plugins_reported_by_package_in_json(broken_site, tmp_path):
    result = gearlab("plugins", "--json", path=broken_site, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    rows = json.loads(result.stdout)
    problems = {r["package"]: r["problem"] for r in rows if r["kind"] == "problem"}
    assert set(problems) == set(EXPECTED_PROBLEMS)
    for package, text in EXPECTED_PROBLEMS.items():
        assert text in problems[package], problems[package]
    faults = {r["name"]: r["package"] for r in rows if r["kind"] == "fault"}
    assert faults == {name: "gearlab" for name in BUILTIN_FAULTS}  # no bump; crack still the built-in
    assert {r["name"] for r in rows if r["kind"] == "adapter"} >= {"mmd", "dann"}


def test_broken_plugins_reported_by_package_in_the_table(broken_site, tmp_path):
    result = gearlab("plugins", path=broken_site, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    lines = [line for line in result.stdout.splitlines() if line.startswith("problem:")]
    assert len(lines) == 3, result.stdout
    for package, text in EXPECTED_PROBLEMS.items():
        assert any(f"package '{package}'" in line and text in line for line in lines), (package, lines)
    for name in BUILTIN_FAULTS:
        assert re.search(rf"│ fault\s+│ {name}\s+│ gearlab\s+│", result.stdout), name


def test_builtin_crack_still_works_beside_broken_plugins(broken_site, tmp_path, registry, pairs, models):
    result = gearlab("stiffness", "--preset", "luo2019", "--fault", "crack@3=5", path=broken_site, cwd=tmp_path)
    mean = printed_mean(result)
    expected = models["luo2019"].mesh_stiffness([place_fault(registry, pairs["luo2019"], "crack", 3, 5)]).mean
    assert math.isclose(mean, float(f"{expected:.5g}"))
    assert mean < models["luo2019"].mesh_stiffness().mean
