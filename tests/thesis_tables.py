"""The lumped parameters as the thesis publishes them, typed from the tables: Table 2.3 (Luo et
al. 2019b) and Table 2.4 (Meng et al. 2020 with Chaari et al. 2012 and Mohammed et al. 2015).
tests/test_gearbox.py checks the built-in descriptions (and so the models' presets) against them,
tests/test_dynamics.py the assembled matrices; PAIR_* are the gear pairs' module and teeth."""

TABLE_2_3 = {
    "m1": 1.272, "m2": 3.5367, "mf": 18.509, "I11": 0.016107, "I12": 0.0001751, "I21": 0.006828,
    "I22": 0.005153, "k_b": 8.5364e7, "c_b": 2.134e4, "k_c": 330.0, "c_c": 23.1, "k_xf": 1.9912e8,
    "k_yf": 2.036e8, "c_xf": 1995.56, "c_yf": 2005.80, "zeta": 0.07,
}  # fmt: skip
TABLE_2_4 = {
    "m1": 0.3083, "m2": 0.4439, "I11": 0.0043, "I12": 0.96e-4, "I21": 2e-4, "I22": 0.0045, "k_b": 6.56e8,
    "c_b": 1.8e3, "k_c": 1e4, "c_c": 10.0, "zeta": 0.07,
}  # fmt: skip
PAIR_2_3 = {"module": 3.175e-3, "Z1": 16, "Z2": 48}
PAIR_2_4 = {"module": 2e-3, "Z1": 25, "Z2": 30}
