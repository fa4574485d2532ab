"""Parameter presets of thesis Tables 2.3 and 2.4 (masses, inertias, bearings, couplings)."""

# Table 2.3, Luo et al. (2019b): Dataset A. Speeds 8.1 and 25.2 Hz, load 7 N*m.
LUO2019 = {
    "pair": "luo2019",
    "params": {
        "m1": 1.272,
        "m2": 3.5367,
        "mf": 18.509,
        "I11": 0.016107,
        "I12": 0.0001751,
        "I21": 0.006828,
        "I22": 0.005153,
        "k_b": 8.5364e7,
        "c_b": 2.134e4,
        "k_c": 330.0,
        "c_c": 23.1,
        "k_xf": 1.9912e8,
        "k_yf": 2.036e8,
        "c_xf": 1995.56,
        "c_yf": 2005.80,
        "zeta": 0.07,
    },
    "speeds_hz": (8.1, 25.2),
    "loads_nm": (7.0,),
    "speed_hz": 25.2,
    "load_nm": 7.0,
}

# Table 2.4, Meng et al. (2020) with the motor and load of Chaari et al. (2012) and the
# couplings of Mohammed et al. (2015): Dataset B. Speed 40 Hz, loads 10, 20, 30 N*m.
MENG2020 = {
    "pair": "meng2020",
    "params": {
        "m1": 0.3083,
        "m2": 0.4439,
        "I11": 0.0043,
        "I12": 0.96e-4,
        "I21": 2e-4,
        "I22": 0.0045,
        "k_b": 6.56e8,
        "c_b": 1.8e3,
        "k_c": 1e4,
        "c_c": 10.0,
        "zeta": 0.07,
    },
    "speeds_hz": (40.0,),
    "loads_nm": (10.0, 20.0, 30.0),
    "speed_hz": 40.0,
    "load_nm": 20.0,
}


def only(preset: dict, names) -> dict:
    """The preset restricted to the parameters a smaller model has."""
    return {**preset, "params": {k: v for k, v in preset["params"].items() if k in names}}
