"""Built-in effect plugins: unmodelled effects for the sim-to-real gap diagnosis (docs/gap.md).

Model level: casing_path, drive_inertias, bearing_stiffness, mesh_damping.
Excitation level: speed_fluctuation, load_fluctuation, shaft_eccentricity, tooth_friction, fillet_correction.
Signal level: sensor_noise, sensor_bandwidth, sensor_lowpass, interference_tone.
"""
