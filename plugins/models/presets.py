"""The thesis's model presets, read from the built-in gearbox descriptions (one path for a preset
and a description): gearlab/gearbox/presets/luo2019.toml holds Table 2.3, meng2020.toml Table
2.4; tests/test_gearbox.py keeps them equal to the tables. Here: the operating points of the
datasets that use them."""

# Luo et al. (2019b): Dataset A at 8.1 and 25.2 Hz, 7 N*m (the description's: 25.2 Hz).
LUO2019 = {"speeds_hz": (8.1, 25.2), "loads_nm": (7.0,)}

# Meng et al. (2020) with the motor and load of Chaari et al. (2012) and the couplings of
# Mohammed et al. (2015): Dataset B at 40 Hz, 10, 20 and 30 N*m (the description's: 20 N*m).
MENG2020 = {"speeds_hz": (40.0,), "loads_nm": (10.0, 20.0, 30.0)}
